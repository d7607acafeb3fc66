"""Planner-independent path metrics: exact collision and clearance, length, smoothness."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from pathfuse.grid import GridMap
from pathfuse.metrics import (
    collision_free,
    evaluate,
    in_bounds,
    min_clearance,
    n_steps,
    path_length,
    r_ratio,
    segment_clearances,
    smoothness,
)
from pathfuse.result import ConfigError, PlanResult, QueryError, Status

# 5 x 5 map, 1 m cells, origin (0, 0): obstacle squares [2,3]x[2,3] and a diagonal pair
#   row 4  .....
#   row 3  .#...     square [1,2] x [3,4]
#   row 2  ..#..     square [2,3] x [2,3]
#   row 1  .....
#   row 0  .....
MAP = GridMap.from_rows([".....", ".#...", "..#..", ".....", "....."])


# ------------------------------------------------------------------ collisions
def test_segment_through_an_obstacle_is_caught():
    assert not collision_free(MAP, [[0.5, 2.5], [4.5, 2.5]])
    # even when both endpoints are far from it and no vertex is inside
    assert not collision_free(MAP, [[0.5, 0.5], [4.5, 4.5]])


def test_corner_cutting_diagonal_is_caught():
    # from cell (row 2, col 1) to (row 3, col 2): the segment passes exactly through
    # the shared corner (2, 3) of the occupied squares [1,2]x[3,4] and [2,3]x[2,3]
    p = [[1.5, 2.5], [2.5, 3.5]]
    assert not collision_free(MAP, p)
    assert min_clearance(MAP, p) == 0.0
    # the same move one cell to the right is clear of both squares
    assert collision_free(MAP, [[2.5, 1.5], [3.5, 2.5]]) is False  # touches corner (3, 2)
    assert collision_free(MAP, [[3.5, 1.5], [4.5, 2.5]])


def test_single_corner_touch_is_a_collision_for_a_point_robot():
    # square [2,3]x[2,3]; the segment from (1.5, 2.5) to (2.5, 1.5) touches its corner (2, 2)
    p = [[1.5, 2.5], [2.5, 1.5]]
    assert min_clearance(MAP, p) == 0.0
    assert not collision_free(MAP, p)


def test_clear_path_passes():
    p = [[0.5, 0.5], [4.5, 0.5], [4.5, 4.5], [1.5, 4.5]]
    assert collision_free(MAP, p)
    assert min_clearance(MAP, p) == pytest.approx(0.5)  # last segment above [1,2]x[3,4]


def test_disc_robot_radius():
    p = [[0.5, 0.5], [4.5, 0.5]]  # 1.5 m below the square [2,3]x[2,3]
    assert min_clearance(MAP, p) == pytest.approx(1.5)
    assert collision_free(MAP, p, robot_radius_m=1.5)  # touching at exactly r is allowed
    assert not collision_free(MAP, p, robot_radius_m=1.5 + 1e-9)
    with pytest.raises(ConfigError, match="robot_radius_m"):
        collision_free(MAP, p, robot_radius_m=-1)


def test_leaving_the_map_is_not_collision_free():
    p = [[0.5, 0.5], [-0.5, 0.5]]
    assert not in_bounds(MAP, p)
    assert not collision_free(MAP, p)


def test_bad_paths_raise():
    with pytest.raises(QueryError, match="point 1"):
        collision_free(MAP, [[0.5, 0.5], [np.nan, 1.0]])
    with pytest.raises(QueryError, match="shape"):
        path_length(np.zeros((3, 3)))


def test_empty_and_single_point_paths():
    assert collision_free(MAP, np.zeros((0, 2)))
    assert path_length(np.zeros((0, 2))) == 0.0 and n_steps(np.zeros((0, 2))) == 0
    assert min_clearance(MAP, [[0.5, 0.5]]) == pytest.approx(math.hypot(1.5, 1.5))
    assert not collision_free(MAP, [[2.5, 2.5]])  # a point inside an obstacle
    free = GridMap(np.zeros((3, 3), dtype=bool))
    assert min_clearance(free, [[0.5, 0.5], [2.5, 2.5]]) == math.inf


# ------------------------------------------------------------------ clearance
def test_clearance_hand_cases():
    # point to the corner (3, 2) of square [2,3]x[2,3]: (3.3, 1.6) -> hypot(0.3, 0.4) = 0.5
    assert min_clearance(MAP, [[3.3, 1.6]]) == pytest.approx(0.5)
    # segment passing the corner (3, 3) at distance: line x + y = 7 -> |3 + 3 - 7| / sqrt 2
    assert min_clearance(MAP, [[3.0, 4.0], [4.0, 3.0]]) == pytest.approx(1 / math.sqrt(2))
    # segment parallel to the square's right edge at 0.25 m
    assert min_clearance(MAP, [[3.25, 0.2], [3.25, 2.6]]) == pytest.approx(0.25)
    np.testing.assert_allclose(
        segment_clearances(MAP, [[0.5, 0.5], [4.5, 0.5], [4.5, 4.5]]), [1.5, 1.5]
    )


def _brute_clearance(grid: GridMap, path: np.ndarray) -> float:
    """Dense sampling against every square: an upper bound within the sampling step."""
    p = np.asarray(path, dtype=float)
    pts = [p[0]]
    for a, b in zip(p[:-1], p[1:], strict=True):
        t = np.linspace(0, 1, 4001)[:, None]
        pts.append(a + t * (b - a))
    pts = np.vstack(pts)
    cells = np.argwhere(grid.occupied)
    lo = np.stack([grid.origin[0] + cells[:, 1] * grid.resolution,
                   grid.origin[1] + cells[:, 0] * grid.resolution], axis=1)
    hi = lo + grid.resolution
    dx = np.maximum(np.maximum(lo[None, :, 0] - pts[:, None, 0], pts[:, None, 0] - hi[None, :, 0]),
                    0)
    dy = np.maximum(np.maximum(lo[None, :, 1] - pts[:, None, 1], pts[:, None, 1] - hi[None, :, 1]),
                    0)
    return float(np.hypot(dx, dy).min())


@settings(max_examples=150, deadline=None)
@given(st.integers(0, 1000), st.lists(st.tuples(st.floats(0, 9), st.floats(0, 7)), min_size=2,
                                      max_size=5))
def test_clearance_matches_brute_force(seed, pts):
    rng = np.random.default_rng(seed)
    g = GridMap(rng.random((7, 9)) < 0.15, resolution=1.0, origin=(0.0, 0.0))
    if not g.occupied.any():
        return
    path = np.array(pts)
    exact = min_clearance(g, path)
    brute = _brute_clearance(g, path)
    seg_len = max(np.hypot(*np.diff(path, axis=0).T).max(), 1e-12)
    # exact <= brute (the samples lie on the path) and brute - exact <= sampling step
    assert exact <= brute + 1e-12
    assert brute - exact <= seg_len / 4000 + 1e-9
    assert collision_free(g, path) == (exact > 0)


# ------------------------------------------------------------------ length, smoothness, steps
def test_length_and_steps():
    p = [[0, 0], [3, 4], [3, 4], [6, 8]]
    assert path_length(p) == pytest.approx(10.0)
    assert n_steps(p) == 3


def test_smoothness_hand_cases():
    assert smoothness([[0, 0], [1, 0], [2, 0]]) == 0.0
    assert smoothness([[0, 0], [1, 0], [1, 1]]) == pytest.approx(math.pi / 2)
    # zigzag: +45, -90, +90 degrees -> 45 + 90 + 90 = 225 degrees
    z = [[0, 0], [1, 0], [2, 1], [3, 0], [4, 1]]
    assert smoothness(z) == pytest.approx(math.radians(45 + 90 + 90))
    assert smoothness([[0, 0], [1, 0], [0, 0]]) == pytest.approx(math.pi)  # U-turn
    # wrapping: heading 170 deg then -170 deg is a 20 degree turn, not 340
    a, b = math.radians(170), math.radians(-170)
    p = [[0, 0], [math.cos(a), math.sin(a)], [math.cos(a) + math.cos(b), math.sin(a) + math.sin(b)]]
    assert smoothness(p) == pytest.approx(math.radians(20))


def test_r_ratio():
    assert r_ratio(14.2182, 14.7279) == pytest.approx((14.2182 - 14.7279) / 14.7279)
    assert r_ratio(2.0, 2.0) == 0.0
    with pytest.raises(ConfigError, match="non-zero"):
        r_ratio(1.0, 0.0)
    with pytest.raises(ConfigError):
        r_ratio(float("nan"), 1.0)


def test_evaluate_dict():
    res = PlanResult(Status.SUCCESS, np.array([[0.5, 0.5], [4.5, 0.5], [4.5, 4.5]]), length=8.0,
                     time_s=0.25, planner="x", iterations=7)
    m = evaluate(MAP, res)
    assert m["length_m"] == pytest.approx(8.0)
    assert m["steps"] == 2
    assert m["collision_free"] and m["in_bounds"] and m["success"]
    assert m["smoothness_rad"] == pytest.approx(math.pi / 2)
    assert m["min_clearance_m"] == pytest.approx(1.5)
    assert (m["status"], m["planner"], m["time_s"], m["iterations"]) == ("SUCCESS", "x", 0.25, 7)
    assert not evaluate(MAP, res, robot_radius_m=2.0)["collision_free"]
    bad = PlanResult(Status.NO_PATH)
    mb = evaluate(MAP, bad)
    assert mb["length_m"] == 0.0 and mb["steps"] == 0 and not mb["success"]


# ------------------------------------------------------------------ exact brute force
def _orient(a, b, c):
    """Sign of the cross product (b - a) x (c - a)."""
    v = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    return (v > 0) - (v < 0)


def _on_segment(a, b, c):
    """c, collinear with a and b, lies on the closed segment ab."""
    return min(a[0], b[0]) <= c[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= c[1] <= max(a[1], b[1])


def _segments_meet(a, b, c, d):
    o1, o2, o3, o4 = _orient(a, b, c), _orient(a, b, d), _orient(c, d, a), _orient(c, d, b)
    if o1 != o2 and o3 != o4:
        return True
    return ((o1 == 0 and _on_segment(a, b, c)) or (o2 == 0 and _on_segment(a, b, d))
            or (o3 == 0 and _on_segment(c, d, a)) or (o4 == 0 and _on_segment(c, d, b)))


def _point_segment_sq(p, a, b):
    vx, vy = b[0] - a[0], b[1] - a[1]
    l2 = vx * vx + vy * vy
    t = 0 if l2 == 0 else ((p[0] - a[0]) * vx + (p[1] - a[1]) * vy) / l2
    t = min(max(t, 0), 1)
    dx, dy = p[0] - (a[0] + t * vx), p[1] - (a[1] + t * vy)
    return dx * dx + dy * dy


def _segment_square_sq(a, b, x0, y0, x1, y1):
    """Squared distance between segment ab and the closed square (exact for Fractions)."""
    if any(x0 <= p[0] <= x1 and y0 <= p[1] <= y1 for p in (a, b)):
        return 0
    corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
    edges = list(zip(corners, corners[1:] + corners[:1], strict=True))
    if any(_segments_meet(a, b, c, d) for c, d in edges):
        return 0
    # disjoint convex sets: the closest pair lies on ab and on one of the square's edges,
    # and two disjoint segments are closest at an end point of one of them
    return min(min(_point_segment_sq(a, c, d), _point_segment_sq(b, c, d),
                   _point_segment_sq(c, a, b), _point_segment_sq(d, a, b)) for c, d in edges)


def _brute_segment_clearances(grid: GridMap, path: np.ndarray, exact=True) -> list[float]:
    """Every segment against every occupied square, in rationals (exact) or floats, then sqrt."""
    num = Fraction if exact else float
    pts = [(num(x), num(y)) for x, y in path.tolist()]
    segs = list(zip(pts[:-1], pts[1:], strict=True)) if len(pts) > 1 else [(pts[0], pts[0])]
    res = num(grid.resolution)
    ox, oy = num(grid.origin[0]), num(grid.origin[1])
    squares = [(ox + c * res, oy + r * res, ox + (c + 1) * res, oy + (r + 1) * res)
               for r, c in np.argwhere(grid.occupied).tolist()]
    out = []
    for a, b in segs:
        d2 = min((_segment_square_sq(a, b, *sq) for sq in squares), default=None)
        out.append(math.inf if d2 is None else math.sqrt(d2))
    return out


# coordinates in cells: lattice values (corners, edges, centres, quarter points; exact in
# binary, so touching is decided exactly), any float, and points outside the map
_CELL_COORD = st.one_of(
    st.integers(-8, 32).map(lambda k: k / 4),
    st.floats(-2.0, 8.0, allow_nan=False, allow_infinity=False),
)


@settings(max_examples=200, deadline=None)
@given(
    occ=st.integers(1, 6).flatmap(lambda h: st.integers(1, 6).flatmap(
        lambda w: st.lists(st.booleans(), min_size=h * w, max_size=h * w).map(
            lambda v: np.array(v, dtype=bool).reshape(h, w)))),
    res=st.sampled_from([1.0, 0.5, 0.25, 2.0]),
    origin=st.tuples(*[st.sampled_from([0.0, -0.5, 1.25, -3.0])] * 2),
    cells=st.lists(st.tuples(_CELL_COORD, _CELL_COORD), min_size=1, max_size=6),
)
# along the top edge of square [1,2]x[1,2], then through the corner it shares with [0,1]x[0,1]
@example(occ=np.eye(3, dtype=bool), res=1.0, origin=(0.0, 0.0),
         cells=[(-1.0, 2.0), (3.0, 2.0), (0.0, 2.0), (2.0, 0.0)])
# a diagonal between two squares touching at a corner, and a point far outside the map
@example(occ=np.eye(2, dtype=bool)[::-1].copy(), res=0.5, origin=(-0.5, 1.25),
         cells=[(0.0, 0.0), (2.0, 2.0), (7.75, -2.0)])
# a subnormal clearance first (its square underflows to 0), then a touching segment
@example(occ=np.array([[False], [True], [False]]), res=1.0, origin=(0.0, 0.0),
         cells=[(-5e-324, 1.0), (0.0, 0.0), (0.0, 4.25)])
def test_segment_clearances_match_exact_brute_force(occ, res, origin, cells):
    g = GridMap(occ, resolution=res, origin=origin)
    path = np.asarray(origin) + np.array(cells) * res
    got = segment_clearances(g, path)
    want = _brute_segment_clearances(g, path)
    assert got.shape == (max(len(cells) - 1, 1),)
    lattice = all((4 * v).is_integer() for pt in cells for v in pt)
    for d, w in zip(got.tolist(), want, strict=True):
        if math.isinf(w):
            assert d == math.inf
        elif lattice:  # exact input: touching must be exactly 0, and only touching
            assert (d == 0.0) == (w == 0.0), (d, w)
            assert d == pytest.approx(w, rel=1e-12, abs=1e-12)
        else:
            assert d == pytest.approx(w, rel=1e-9, abs=1e-9 * res)
    assert min_clearance(g, path) == (got.min() if got.size else math.inf)
    assert collision_free(g, path) == (in_bounds(g, path) and bool(got.min() > 0))


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_sparse_maps_match_brute_force(seed):
    # sparse maps (up to 40 x 40) with long segments (in, across and out of the map) or short
    # steps far from any obstacle: the cases the ring search hands over to the pyramid.
    # Drawn from the seed, not shrunk towards small maps, where rings settle everything.
    rng = np.random.default_rng(seed)
    shape = tuple(rng.integers(1, 41, 2).tolist())
    g = GridMap(rng.random(shape) < rng.choice([0.002, 0.01, 0.03]))
    n = int(rng.integers(2, 9))
    if rng.random() < 0.5:
        path = rng.uniform(-10, 50, (n, 2))
    else:
        path = rng.uniform(-5, 45, 2) + np.cumsum(rng.uniform(-1, 1, (n, 2)), axis=0)
    got = segment_clearances(g, path).tolist()
    want = _brute_segment_clearances(g, path, exact=False)  # floats: fast enough for 300 maps
    assert got == pytest.approx(want, rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("a, b", [((-3.0, 2.3), (53.0, 47.9)), ((51.7, -2.2), (1.1, 44.4)),
                                  ((-4.0, 20.2), (55.0, 31.7))])
def test_long_segment_finds_an_obstacle_anywhere_along_it(a, b):
    # one long segment on a 50 x 50 map; two decoy squares on the bottom row, far from it,
    # and a third square at every cell within 6 m of its line in turn, so that the
    # nearest square is tried at every place along the segment and on both sides
    path = np.array([a, b])
    (ax, ay), (dx, dy) = a, (b[0] - a[0], b[1] - a[1])
    for r in range(1, 50):
        for c in range(50):
            if abs((c + 0.5 - ax) * dy - (r + 0.5 - ay) * dx) > 6 * math.hypot(dx, dy):
                continue
            occ = np.zeros((50, 50), dtype=bool)
            occ[0, 0] = occ[0, 49] = occ[r, c] = True
            g = GridMap(occ)
            want = _brute_segment_clearances(g, path, exact=False)
            assert segment_clearances(g, path).tolist() == pytest.approx(want, rel=1e-12), (r, c)
