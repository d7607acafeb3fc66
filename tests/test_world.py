"""The simulated world: exact continuous collision geometry, obstacle motion, World.reset/step."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pathfuse import GridMap, QueryError
from pathfuse.result import PathfuseError
from pathfuse.sweep import disc_sweep_gaps, segment_static_distance
from pathfuse.world import (
    LinearObstacle,
    PatrolObstacle,
    RandomWalkObstacle,
    World,
    load_scenario,
)

# ----------------------------------------------------------------------------- oracles
# Independent of the code under test: a segment/box distance by the separating-axis
# intersection test plus vertex distances, and a brute loop over *every* occupied cell.


def _pt_seg(p, a, b):
    a, b, p = (np.asarray(v, float) for v in (a, b, p))
    d = b - a
    l2 = float(d @ d)
    t = 0.0 if l2 == 0 else min(1.0, max(0.0, float((p - a) @ d) / l2))
    return float(np.linalg.norm(a + t * d - p))


def _pt_box(p, box):
    x0, y0, x1, y1 = box
    return math.hypot(max(x0 - p[0], 0, p[0] - x1), max(y0 - p[1], 0, p[1] - y1))


def _seg_meets_box(a, b, box):
    """Separating axis theorem on the segment and the box (x, y and the segment's normal)."""
    x0, y0, x1, y1 = box
    if max(a[0], b[0]) < x0 or min(a[0], b[0]) > x1 or max(a[1], b[1]) < y0 \
            or min(a[1], b[1]) > y1:
        return False
    n = (-(b[1] - a[1]), b[0] - a[0])
    corners = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]
    proj = [n[0] * (c[0] - a[0]) + n[1] * (c[1] - a[1]) for c in corners]
    return min(proj) <= 0 <= max(proj)


def _seg_box(a, b, box):
    if _seg_meets_box(a, b, box):
        return 0.0
    x0, y0, x1, y1 = box
    cands = [_pt_box(a, box), _pt_box(b, box)]
    cands += [_pt_seg(c, a, b) for c in [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]]
    return min(cands)


def _brute_static(grid: GridMap, a, b) -> float:
    x0, y0, x1, y1 = grid.bounds
    best = min(min(p[0] - x0, x1 - p[0], p[1] - y0, y1 - p[1]) for p in (a, b))
    if best <= 0:
        return 0.0
    res = grid.resolution
    for r, c in np.argwhere(grid.occupied):
        bx, by = grid.origin[0] + c * res, grid.origin[1] + r * res
        best = min(best, _seg_box(a, b, (bx, by, bx + res, by + res)))
    return best


def _static(grid, a, b, cap):
    return float(segment_static_distance(grid.occupied, grid.origin[0], grid.origin[1],
                                         grid.resolution, a[0], a[1], b[0], b[1], cap))


# ----------------------------------------------------------------------------- geometry
@settings(max_examples=150, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    h=st.integers(1, 9), w=st.integers(1, 9),
    res=st.sampled_from([0.05, 0.5, 1.0, 2.0]),
    frac=st.lists(st.floats(0.0, 1.0), min_size=4, max_size=4),
)
def test_static_distance_matches_brute_force_over_all_cells(seed, h, w, res, frac):
    rng = np.random.default_rng(seed)
    occ = rng.random((h, w)) < 0.3
    grid = GridMap(occ, resolution=res, origin=(-1.3, 0.7))
    x0, y0, x1, y1 = grid.bounds
    a = (x0 + frac[0] * (x1 - x0), y0 + frac[1] * (y1 - y0))
    b = (x0 + frac[2] * (x1 - x0), y0 + frac[3] * (y1 - y0))
    expect = _brute_static(grid, a, b)
    cap = 100.0
    assert _static(grid, a, b, cap) == pytest.approx(min(expect, cap), abs=1e-9)
    # a small cap returns min(distance, cap) too (the collision check uses cap = radius)
    assert _static(grid, a, b, 0.3 * res) == pytest.approx(min(expect, 0.3 * res), abs=1e-9)


def test_static_distance_leaving_the_map_is_zero():
    g = GridMap.from_rows(["...", "..."])
    assert _static(g, (1.5, 1.0), (3.2, 1.0), 5.0) == 0.0
    assert _static(g, (1.5, 1.0), (1.5, 1.0), 5.0) == pytest.approx(1.0)  # 1 m from the edge


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-3, 3, allow_nan=False), min_size=8, max_size=8),
       st.floats(0.0, 0.5), st.floats(0.05, 0.5))
def test_disc_sweep_gap_is_the_minimum_over_the_tick(v, r1, r2):
    p0, p1 = np.array(v[0:2]), np.array(v[2:4])
    q0, q1 = np.array([v[4:6]]), np.array([v[6:8]])
    got = float(disc_sweep_gaps(p0, p1, r1, q0, q1, np.array([r2]))[0])
    t = np.linspace(0.0, 1.0, 20001)[:, None]
    d = np.linalg.norm((p0 + t * (p1 - p0)) - (q0 + t * (q1 - q0)), axis=1)
    sampled = float(d.min()) - r1 - r2
    assert got <= sampled + 1e-12          # the closed form is never above a sample
    step = float(np.linalg.norm((p1 - p0) - (q1 - q0))) / 20000
    assert got >= sampled - step - 1e-12   # and within one sampling step below


# ----------------------------------------------------------------------------- World basics
EMPTY = ["." * 10] * 6


def _world(obstacles=(), **kw):
    doc = {"map": {"rows": EMPTY}, "start": [1.5, 3.0], "goal": [8.5, 3.0],
           "robot": {"radius": 0.2, "max_speed": 1.0, "sensing_radius": 3.0},
           "dt": 0.1, "obstacles": list(obstacles)}
    doc.update(kw)
    return World(load_scenario(doc))


def test_reset_step_and_the_speed_limit():
    w = _world()
    obs = w.reset()
    assert obs.tick == 0 and obs.time == 0.0 and obs.position.tolist() == [1.5, 3.0]
    obs, term, trunc, info = w.step((3.0, 4.0))     # 5 m/s -> clipped to 1 m/s
    assert info["clipped"] and not term and not trunc
    assert obs.position == pytest.approx([1.5 + 0.06, 3.0 + 0.08])
    assert obs.velocity == pytest.approx([0.6, 0.8])
    assert obs.tick == 1 and obs.time == pytest.approx(0.1)


def test_bad_actions_and_stepping_a_finished_episode_raise():
    w = _world(time_limit=0.2)
    w.reset()
    with pytest.raises(QueryError, match="finite velocity"):
        w.step((np.nan, 0.0))
    with pytest.raises(QueryError, match="velocity"):
        w.step((1.0, 2.0, 3.0))
    w.step((0.0, 0.0))
    _, term, trunc, _ = w.step((0.0, 0.0))
    assert trunc and not term
    with pytest.raises(PathfuseError, match="reset"):
        w.step((0.0, 0.0))


def test_goal_is_reached_when_the_step_passes_within_tolerance():
    # the step jumps over the goal: its end points are 0.3 m away, the segment passes through it
    w = _world(goal=[2.0, 3.0], dt=0.6, goal_tolerance=0.1)
    w.reset()
    _, term, _, info = w.step((1.0, 0.0))           # 1.5 -> 2.1 passes x = 2.0
    assert term and info["event"] == "reached"


def test_time_limit_truncates_after_ceil_ticks():
    w = _world(time_limit=1.05)
    w.reset()
    n = 0
    while True:
        n += 1
        _, term, trunc, _ = w.step((0.0, 0.0))
        if term or trunc:
            break
    assert trunc and n == 11


# ----------------------------------------------------------------------------- collisions
def test_disc_crossing_the_step_between_ticks_is_caught():
    # robot 1.5 -> 2.5 along y = 3 in one tick (1 s); a disc of radius 0.1 goes from
    # (2, 4) to (2, 2): at both ticks the gap is > 0.7 m, at mid-tick they overlap.
    ob = {"position": [2.0, 4.0], "velocity": [0.0, -2.0], "radius": 0.1}
    w = _world([ob], dt=1.0, robot={"radius": 0.1, "max_speed": 2.0})
    w.reset()
    q0, q1 = w.obstacle_positions[0, 0], w.obstacle_positions[1, 0]
    assert q0.tolist() == [2.0, 4.0] and q1.tolist() == [2.0, 2.0]
    assert np.hypot(*(np.array([1.5, 3.0]) - q0)) - 0.2 > 0.7
    assert np.hypot(*(np.array([2.5, 3.0]) - q1)) - 0.2 > 0.7
    _, term, _, info = w.step((1.0, 0.0))
    assert term and info["event"] == "collision" and info["collision"] == 0
    assert info["obstacle_gap"] == pytest.approx(-0.2)


def test_near_miss_disc_is_not_a_collision():
    # same crossing, but the disc passes 1 s later: min gap exactly computable
    ob = {"position": [2.0, 6.0], "velocity": [0.0, -2.0], "radius": 0.1}
    w = _world([ob], dt=1.0, robot={"radius": 0.1, "max_speed": 2.0},
               map={"rows": ["." * 10] * 8})
    w.reset()
    _, term, _, info = w.step((1.0, 0.0))
    assert not term
    # robot (1.5 + t, 3), disc (2, 6 - 2t): closest at t = 1 -> (2.5, 3) vs (2, 4)
    assert info["obstacle_gap"] == pytest.approx(math.hypot(0.5, 1.0) - 0.2)


def test_step_through_a_static_cell_corner_is_caught():
    # cell (row 1, col 1) = square [1, 2] x [1, 2]; a 0.1 m robot steps from (0.8, 1.3)
    # to (1.3, 0.8): both end points are 0.2 m from the square, the segment cuts its corner
    rows = ["....", "....", ".#..", "...."]
    doc = {"map": {"rows": rows}, "start": [0.8, 1.3], "goal": [3.5, 3.5],
           "robot": {"radius": 0.1, "max_speed": 10.0}, "dt": 1.0}
    w = World(load_scenario(doc))
    w.reset()
    assert w.static_gap(np.array([1.3, 0.8])) == pytest.approx(0.1)
    _, term, _, info = w.step((0.5, -0.5))
    assert term and info["collision"] == "static"


def test_near_miss_of_a_static_corner_is_not_a_collision():
    rows = ["....", "....", ".#..", "...."]
    doc = {"map": {"rows": rows}, "start": [0.5, 1.1], "goal": [3.5, 3.5],
           "robot": {"radius": 0.1, "max_speed": 10.0}, "dt": 1.0}
    w = World(load_scenario(doc))
    w.reset()
    _, term, _, info = w.step((0.6, -0.6))   # (0.5, 1.1) -> (1.1, 0.5): 0.283 m off the corner
    assert not term
    assert info["static_gap"] == pytest.approx(0.4 / math.sqrt(2) - 0.1)


def test_leaving_the_map_is_a_static_collision():
    w = _world(start=[0.3, 3.0])
    w.reset()
    _, term, _, info = w.step((-1.0, 0.0))
    assert term and info["collision"] == "static"


# ----------------------------------------------------------------------------- sensing
def test_observation_holds_only_discs_in_range_with_past_velocities():
    obs_specs = [
        {"position": [3.0, 3.0], "velocity": [0.5, 0.0], "radius": 0.3},   # near
        {"position": [9.0, 3.0], "velocity": [0.0, 0.5], "radius": 0.3},   # 7.5 m away
    ]
    w = _world(obs_specs)
    obs = w.reset()
    assert obs.obstacles.ids.tolist() == [0]
    assert obs.obstacles.velocities.tolist() == [[0.5, 0.0]]
    assert obs.obstacles.radii.tolist() == [0.3]
    for _ in range(5):
        obs, *_ = w.step((0.0, 0.0))
    k = obs.tick
    # the sensed position is the disc's now, and its velocity the last tick's displacement
    assert obs.obstacles.positions[0] == pytest.approx(w.obstacle_positions[k, 0])
    assert obs.obstacles.velocities[0] == pytest.approx(
        (w.obstacle_positions[k, 0] - w.obstacle_positions[k - 1, 0]) / w.dt)


# ----------------------------------------------------------------------------- motion
ROOM = GridMap.from_rows([
    "..........",
    "..........",
    "...##.....",
    "...##...#.",
    "..........",
    "......#...",
    "..........",
])


def _independent_free(grid, a, b, r):
    return _brute_static(grid, a, b) >= r - 1e-9


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_bouncing_disc_stays_in_the_map_out_of_cells_at_constant_speed(seed):
    rng = np.random.default_rng(seed)
    ob = LinearObstacle((1.0, 1.0), tuple(rng.uniform(-1.5, 1.5, 2)), 0.3)
    dt = 0.1
    pos, vel = ob.trajectory(ROOM, dt, 400)
    steps = np.hypot(*np.diff(pos, axis=0).T)
    assert steps == pytest.approx(np.full(400, ob.speed * dt), rel=1e-12)
    for k in range(0, 400, 3):  # every third tick, by the brute-force oracle
        assert _independent_free(ROOM, pos[k], pos[k + 1], 0.3)
    # it did bounce (the velocity changed) and it is deterministic
    assert len({tuple(np.round(v, 9)) for v in vel[1:]}) > 1
    pos2, _ = ob.trajectory(ROOM, dt, 400)
    assert np.array_equal(pos, pos2)


def test_bounce_reflects_the_blocking_axis_only():
    g = GridMap.from_rows(["....."] * 3)
    ob = LinearObstacle((4.0, 1.5), (1.0, 0.2), 0.5)
    pos, vel = ob.trajectory(g, 0.5, 2)
    assert vel[1].tolist() == [1.0, 0.2]      # touching the edge (x = 4.5) is allowed
    assert vel[2].tolist() == [-1.0, 0.2]     # x reflected at the right edge, y kept
    assert pos[2].tolist() == pytest.approx([4.0, 1.7])


def test_patrol_back_and_forth_and_loop():
    g = GridMap.from_rows(["......"] * 6)
    tri = ((1.0, 1.0), (5.0, 1.0), (5.0, 4.0))
    loop = PatrolObstacle(tri, speed=1.0, radius=0.3, loop=True)
    back = PatrolObstacle(tri, speed=1.0, radius=0.3, loop=False)
    # loop: perimeter 4 + 3 + 5 = 12 m; back and forth: period 2 * 7 = 14 m
    p = loop.positions_at(np.array([0.0, 2.0, 5.5, 9.5, 12.0]))
    np.testing.assert_allclose(p, [[1, 1], [3, 1], [5, 2.5], [3, 2.5], [1, 1]], atol=1e-12)
    q = back.positions_at(np.array([0.0, 7.0, 8.0, 11.0, 14.0]))
    np.testing.assert_allclose(q, [[1, 1], [5, 4], [5, 3], [4, 1], [1, 1]], atol=1e-12)
    pos, _ = loop.trajectory(g, 0.1, 300)
    steps = np.hypot(*np.diff(pos, axis=0).T)
    assert steps.max() <= 0.1 + 1e-12
    assert np.mean(np.isclose(steps, 0.1)) > 0.9    # only corner ticks are shorter


def test_random_walk_is_seeded_constant_speed_and_free():
    ob = RandomWalkObstacle((1.0, 1.0), speed=0.8, radius=0.25, seed=3)
    pos, _ = ob.trajectory(ROOM, 0.1, 500)
    again, _ = RandomWalkObstacle((1.0, 1.0), speed=0.8, radius=0.25, seed=3).trajectory(
        ROOM, 0.1, 500)
    other, _ = RandomWalkObstacle((1.0, 1.0), speed=0.8, radius=0.25, seed=4).trajectory(
        ROOM, 0.1, 500)
    assert np.array_equal(pos, again)
    assert not np.array_equal(pos, other)
    ep_seed, _ = ob.trajectory(ROOM, 0.1, 500, seed=7)  # an episode seed changes the walk
    assert not np.array_equal(pos, ep_seed)
    assert np.hypot(*np.diff(pos, axis=0).T) == pytest.approx(np.full(500, 0.08), rel=1e-9)
    for k in range(0, 500, 5):
        assert _independent_free(ROOM, pos[k], pos[k + 1], 0.25)
    x0, y0, x1, y1 = ROOM.bounds
    assert (pos[:, 0] >= x0 + 0.25 - 1e-9).all() and (pos[:, 0] <= x1 - 0.25 + 1e-9).all()
    assert (pos[:, 1] >= y0 + 0.25 - 1e-9).all() and (pos[:, 1] <= y1 - 0.25 + 1e-9).all()


def test_world_reset_replays_obstacles_and_seed_changes_random_walks():
    spec = [{"random_walk": {"position": [5, 3], "speed": 0.5, "seed": 1}, "radius": 0.3}]
    w = _world(spec)
    w.reset()
    a = w.obstacle_positions.copy()
    w.reset()
    assert np.array_equal(a, w.obstacle_positions)
    w.reset(seed=5)
    b = w.obstacle_positions.copy()
    w.reset(seed=5)
    assert np.array_equal(b, w.obstacle_positions)
    assert not np.array_equal(a, b)


def test_clip_action_fast_path_matches_the_general_one():
    # a controller's float64 (2,) array skips the conversion; any other form of the same
    # action is converted and must give the same command, bit for bit
    for diff in (False, True):
        robot = {"radius": 0.2, "max_speed": 1.0, "sensing_radius": 3.0}
        if diff:
            robot.update(model="diff-drive", heading=0.3)
        w = _world(robot=robot)
        w.reset()
        for a in ((0.37, -0.21), (3.0, 4.0), (0.0, 0.0), (-1e-300, 5e-324)):
            fast, clipped = w.clip_action(np.array(a, dtype=np.float64))
            for other in (a, list(a), np.array([[a[0], 9.0], [a[1], 9.0]])[:, 0],
                          np.array([a])):
                slow, c2 = w.clip_action(other)
                assert slow.tobytes() == fast.tobytes() and c2 == clipped
        for bad in (np.array([np.nan, 0.0]), np.array([0.0, np.inf]), (np.inf, 0.0)):
            with pytest.raises(QueryError, match="finite"):
                w.clip_action(bad)
        with pytest.raises(QueryError):
            w.clip_action(np.zeros(3))


def test_a_world_without_discs_senses_the_same_empty_record():
    w = _world()
    obs0 = w.reset()
    obs1, *_ = w.step((0.1, 0.0))
    s0, s1 = obs0.obstacles, obs1.obstacles
    assert s0 is s1 and len(s0) == 0
    # the same types as freshly made empty arrays (the kernels see one signature)
    for got, fresh in ((s0.ids, np.zeros(0, np.int64)), (s0.positions, np.zeros((0, 2))),
                       (s0.velocities, np.zeros((0, 2))), (s0.radii, np.zeros(0))):
        assert got.dtype == fresh.dtype and got.shape == fresh.shape
        assert got.flags.writeable and got.flags.c_contiguous
