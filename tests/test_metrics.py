"""Planner-independent path metrics: exact collision and clearance, length, smoothness."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
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
