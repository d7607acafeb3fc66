"""mppi's shortcuts return exactly what they replace (bit for bit).

``_track`` (the nearest path segment of every rollout step) leaves out the division of a
projection that clamps and the ``hypot`` of a point whose square is beyond the best so
far; the reference below is the search as it was written before, every segment measured.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pathfuse.field.pathing import polyline_cumlen
from pathfuse.planners.controllers.mppi_kernel import _track


@njit(cache=False)
def _track_reference(px, py, pts, cum, j, k0, fwd, back):
    m = pts.shape[0]
    if m == 1:
        return 0, math.hypot(px - pts[0, 0], py - pts[0, 1]), 0.0
    lo = j
    while lo > k0 and cum[j] - cum[lo - 1] <= back:
        lo -= 1
    hi = j
    while hi < m - 2 and cum[hi + 1] - cum[j] <= fwd:
        hi += 1
    best = j
    bd = np.inf
    bt = 0.0
    for s in range(lo, hi + 1):
        ax = pts[s, 0]
        ay = pts[s, 1]
        vx = pts[s + 1, 0] - ax
        vy = pts[s + 1, 1] - ay
        l2 = vx * vx + vy * vy
        tt = 0.0
        if l2 > 0.0:
            tt = min(max(((px - ax) * vx + (py - ay) * vy) / l2, 0.0), 1.0)
        d = math.hypot(px - (ax + tt * vx), py - (ay + tt * vy))
        if d < bd:
            bd = d
            best = s
            bt = tt
    return best, bd, bt


def _paths(rng: np.random.Generator) -> list[np.ndarray]:
    """Grid paths (BARN's 0.05 m steps), paths that fold back on themselves, repeated
    points (zero-length segments), a single point, tiny and huge coordinates."""
    out = []
    for _ in range(40):
        steps = rng.choice([-1, 0, 1], size=(int(rng.integers(2, 60)), 2)) * 0.05
        out.append(np.cumsum(np.vstack([[-2.0, 3.0], steps]), axis=0))
    for _ in range(20):
        pts = rng.normal(size=(int(rng.integers(2, 30)), 2)) * float(rng.choice([1e-3, 1.0]))
        pts[rng.random(pts.shape[0]) < 0.2] = pts[0]  # repeats
        out.append(pts)
    fold = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 0.0], [1.0, 1e-12], [0.5, 0.0]])
    out += [fold, np.array([[0.3, 0.7]]), fold * 1e-160, fold + 1e6]
    return [np.ascontiguousarray(p, dtype=np.float64) for p in out]


def test_track_shortcuts_are_exact() -> None:
    rng = np.random.default_rng(17)
    calls = clamped = 0
    for pts in _paths(rng):
        cum = polyline_cumlen(pts)
        m = pts.shape[0]
        seg = float(np.diff(cum).max()) if m > 1 else 0.0
        scale = float(np.abs(pts).max()) + 1e-300
        for _ in range(60):
            j = int(rng.integers(0, max(m - 1, 1)))
            k0 = int(rng.integers(0, j + 1))
            a = pts[min(j, m - 1)]
            kind = int(rng.integers(0, 4))
            if kind == 0:  # on a path point or a segment, exactly or nearly
                b = pts[min(j + 1, m - 1)]
                u = float(rng.choice([0.0, 0.5, 1.0]))
                p = a + u * (b - a) + rng.normal(size=2) * float(rng.choice([0.0, 1e-15, 1e-9]))
            else:
                p = a + rng.normal(size=2) * scale * float(rng.choice([1e-3, 0.1, 2.0]))
            fwd = float(rng.choice([0.0, 2.0 * seg, 0.3 + 2.0 * seg, 1e9]))
            back = float(rng.choice([0.0, 2.0 * seg, 1e9]))
            px, py = float(p[0]), float(p[1])
            want = _track_reference(px, py, pts, cum, j, k0, fwd, back)
            got = _track(px, py, pts, cum, j, k0, fwd, back)
            assert got == want, (pts.tolist(), px, py, j, k0, fwd, back, got, want)
            assert math.copysign(1.0, got[1]) == math.copysign(1.0, want[1])
            calls += 1
            clamped += want[2] in (0.0, 1.0)
    assert calls > 3000 and clamped > 1000  # the clamped projections were exercised


def test_track_exact_at_ties_between_segments() -> None:
    # a point equidistant from two segments keeps the first (strict "<"), as before
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0], [0.0, 2.0]])
    cum = polyline_cumlen(pts)
    for px, py in ((0.5, 1.0), (0.5, 1.0 + 1e-16), (1.0, 1.0), (2.0, 1.0)):
        assert _track(px, py, pts, cum, 1, 0, 1e9, 1e9) == \
            _track_reference(px, py, pts, cum, 1, 0, 1e9, 1e9)
