"""The A*-APF fusion planner (Algorithm 2)."""

from __future__ import annotations

import dataclasses
import math
import re
from collections import defaultdict

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from pathfuse import Budget, ConfigError, GridMap, Status, plan
from pathfuse.field.forces import attractive_force, total_force
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.metrics import collision_free, evaluate, path_length, r_ratio
from pathfuse.planners.controllers.fusion import (
    FusionController,
    FusionParams,
    follow_path,
    force_at,
)
from pathfuse.planners.registry import get_planner
from pathfuse.planners.run import warm

START, GOAL = np.array(PAPER_START), np.array(PAPER_GOAL)


def transform(grid: GridMap, quarter_turns: int, mirror: bool):
    """The square map rotated by ``quarter_turns`` x 90 degrees (after an optional
    x-mirror) about its centre, and the matching map of world points."""
    n = grid.width
    assert grid.height == n
    c = np.array(grid.origin) + n * grid.resolution / 2

    def tp(p):
        q = np.asarray(p, dtype=float) - c
        if mirror:
            q = q * [-1, 1]
        for _ in range(quarter_turns % 4):
            q = np.stack([-q[..., 1], q[..., 0]], axis=-1)
        return q + c

    occ = np.zeros_like(grid.occupied)
    new = grid.world_to_cell(tp(grid.cell_to_world(np.argwhere(grid.occupied))))
    occ[new[:, 0], new[:, 1]] = True
    return GridMap(occ, grid.resolution, grid.origin), tp


TRANSFORMS = [(t, m) for t in range(4) for m in (False, True) if (t, m) != (0, False)]


def count_shortest_paths(grid: GridMap, start, goal) -> int:
    """Number of optimal 8-connected no-corner-cutting grid paths (an independent oracle)."""
    h, w = grid.shape
    free = ~grid.occupied
    rows, cols, wts = [], [], []
    rr, cc = np.nonzero(free)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            if dr == dc == 0:
                continue
            r2, c2 = rr + dr, cc + dc
            ok = (r2 >= 0) & (r2 < h) & (c2 >= 0) & (c2 < w)
            r1_, c1_, r2, c2 = rr[ok], cc[ok], r2[ok], c2[ok]
            ok = free[r2, c2]
            if dr and dc:
                ok &= free[r1_, c2] & free[r2, c1_]
            rows.append(r1_[ok] * w + c1_[ok])
            cols.append(r2[ok] * w + c2[ok])
            wts.append(np.full(ok.sum(), math.hypot(dr, dc)))
    rows, cols, wts = np.concatenate(rows), np.concatenate(cols), np.concatenate(wts)
    graph = coo_matrix((wts, (rows, cols)), shape=(h * w, h * w)).tocsr()
    (sr, sc), (gr, gc) = grid.world_to_cell([start, goal])
    s, g = sr * w + sc, gr * w + gc
    ds = dijkstra(graph, indices=s)
    dg = dijkstra(graph.T, indices=g)
    if not np.isfinite(ds[g]):
        return 0
    # lattice lengths a + b sqrt(2) that differ are >= 1e-3 apart on maps this small
    tight = np.abs(ds[rows] + wts + dg[cols] - ds[g]) < 1e-9
    nxt = defaultdict(list)
    for u, v in zip(rows[tight], cols[tight], strict=True):
        nxt[u].append(v)
    count = np.zeros(h * w)
    count[s] = 1
    for u in np.argsort(ds):
        if not np.isfinite(ds[u]):
            break
        for v in nxt[u]:
            count[v] += count[u]
    return int(count[g])


# ------------------------------------------------------------------ registration & basics
def test_registered():
    spec = get_planner("fusion")
    assert spec.params_cls is FusionParams and spec.uses_astar
    assert spec.global_planner == "astar" and spec.controller is FusionController
    assert spec.offline and spec.online and spec.description
    assert callable(spec.controller.warmup)
    warm(spec)
    assert "robot_radius_m" not in spec.defaults()


def test_paper_maps_success_and_safety():
    n, ok = 200, 0
    for seed in range(n):
        g = paper_map(seed)
        r = plan(g, PAPER_START, PAPER_GOAL, planner="fusion")
        assert r.path[0].tolist() == list(PAPER_START)
        m = evaluate(g, r)
        assert m["collision_free"], (seed, r.message)
        if r.success:
            ok += 1
            assert r.path[-1].tolist() == list(PAPER_GOAL)
        else:
            assert r.status is Status.LOCAL_MINIMUM
    assert ok >= 0.99 * n


def test_info_holds_the_astar_run():
    g = paper_map(11)
    r = plan(g, PAPER_START, PAPER_GOAL, planner="fusion")
    a = plan(g, PAPER_START, PAPER_GOAL, planner="astar")
    np.testing.assert_array_equal(r.info["astar_path"], a.path)
    assert r.info["astar_length"] == pytest.approx(path_length(a.path))
    assert 0 < r.info["astar_time_s"] < r.time_s
    assert r.info["step_time_s"] < r.time_s
    assert r.expansions == a.expansions and r.iterations > 0


def test_shorter_than_astar_on_most_paper_maps():
    # the paper's claim (Table I: -3.46 %); measured median R_length -8.8 % on seeds 0-299
    ratios = []
    for seed in range(50):
        r = plan(paper_map(seed), PAPER_START, PAPER_GOAL, planner="fusion")
        ratios.append(r_ratio(r.length, r.info["astar_length"]))
    assert np.median(ratios) < 0


def test_unreachable_goal_returns_astar_status():
    g = GridMap.from_rows([
        "..........",
        "...#####..",
        "...#...#..",
        "...#####..",
        "..........",
    ])
    r = plan(g, (0.5, 0.5), (5.5, 2.5), planner="fusion")
    assert r.status is Status.NO_PATH
    assert r.path.shape == (0, 2) and "A*" in r.message


def test_iteration_cap():
    g = GridMap(np.zeros((5, 40), dtype=bool))
    r = plan(g, (0.5, 2.5), (38.5, 2.5), planner="fusion", budget=Budget(max_iterations=9))
    assert r.status is Status.MAX_ITERATIONS
    assert r.iterations == 9 and len(r.path) == 10
    assert collision_free(g, r.path)


def test_time_limit():
    g = GridMap(np.zeros((5, 40), dtype=bool))
    r = plan(g, (0.5, 2.5), (38.5, 2.5), planner="fusion", step_m=1e-4,
             budget=Budget(time_limit_s=1e-6))
    assert r.status is Status.TIMEOUT


def test_start_at_goal():
    g = GridMap(np.zeros((3, 3), dtype=bool))
    r = plan(g, (1.5, 1.5), (1.5, 1.5), planner="fusion")
    assert r.success and r.path.tolist() == [[1.5, 1.5]]


def test_deterministic():
    g = paper_map(8)
    a = plan(g, PAPER_START, PAPER_GOAL, planner="fusion")
    b = plan(g, PAPER_START, PAPER_GOAL, planner="fusion")
    assert np.array_equal(a.path, b.path)


@pytest.mark.parametrize("seed", range(8))
def test_robot_radius(seed):
    g = paper_map(seed)
    r = plan(g, PAPER_START, PAPER_GOAL, planner="fusion", robot_radius_m=0.3)
    assert collision_free(g, r.path, robot_radius_m=0.3)
    if r.success:
        assert r.path[-1].tolist() == list(PAPER_GOAL)


# ------------------------------------------------------------------ the forces of Algorithm 2
def test_force_sums_goal_path_points_and_repulsion():
    g = GridMap.from_rows([".......", ".......", "..#....", "......."])  # obstacle (2.5, 1.5)
    path = np.array([[0.5, 0.5], [1.5, 0.5], [2.5, 0.5], [3.5, 0.5], [4.5, 1.5], [5.5, 2.5]])
    x, goal = np.array([1.4, 0.7]), np.array([5.5, 2.5])
    p = FusionParams(r1_m=1.5)
    f = force_at(g, x, goal, path, p, progress=1)
    # ahead of progress 1 and strictly inside r1: index 2 only (index 3 is 2.1 m away)
    expected = total_force(x, goal, [[2.5, 1.5]]) + attractive_force(x, path[2])
    assert np.linalg.norm(total_force(x, goal, [[2.5, 1.5]]) - attractive_force(x, goal)) > 0.1
    np.testing.assert_allclose(f, expected)
    # with progress 0 the point at index 1 (0.22 m away) attracts too
    np.testing.assert_allclose(force_at(g, x, goal, path, p, progress=0),
                               expected + attractive_force(x, path[1]))


def test_paper_x_rule_is_the_papers_eq8():
    g = GridMap(np.zeros((4, 8), dtype=bool))
    path = np.array([[3.0, 1.0], [2.6, 1.0], [2.2, 1.0], [1.0, 1.0]])  # towards -x
    x, goal = np.array([2.5, 1.2]), np.array([1.0, 1.0])
    px = FusionParams(ahead="paper-x", r1_m=1.0)
    # eq. 8: only points with x_p > x attract, whatever their place along the path
    expected = attractive_force(x, goal) + attractive_force(x, path[0]) + attractive_force(
        x, path[1])
    np.testing.assert_allclose(force_at(g, x, goal, path, px, progress=3), expected)
    # the direction-free rule takes the points after the progress index instead
    prog = FusionParams(ahead="progress", r1_m=1.0)
    np.testing.assert_allclose(force_at(g, x, goal, path, prog, progress=1),
                               attractive_force(x, goal) + attractive_force(x, path[2]))


def test_paper_x_fails_when_the_goal_is_towards_minus_x():
    # On an open corridor the A* path is straight.  Towards +x the paper's rule attracts
    # the points ahead; towards -x it attracts the points already passed (x_p > x),
    # which pull the robot back until it stalls short of the goal.  The default rule
    # works both ways with the same result.
    g = GridMap(np.zeros((3, 12), dtype=bool))
    east, west = ((0.5, 1.5), (10.5, 1.5)), ((10.5, 1.5), (0.5, 1.5))
    fwd = plan(g, *east, planner="fusion", ahead="paper-x", escape=False)
    back = plan(g, *west, planner="fusion", ahead="paper-x", escape=False)
    assert fwd.success and fwd.length == pytest.approx(10.0)
    assert back.status is Status.LOCAL_MINIMUM
    assert math.dist(back.path[-1], west[1]) > 1.0
    for s, e in (east, west):
        r = plan(g, s, e, planner="fusion")
        assert r.success and r.length == pytest.approx(10.0) and r.info["escapes"] == 0


@pytest.mark.parametrize("seed", range(20))
def test_paper_x_on_paper_maps(seed):
    g = paper_map(seed)
    r = plan(g, PAPER_START, PAPER_GOAL, planner="fusion", ahead="paper-x")
    assert collision_free(g, r.path)
    assert r.success, r.message


# ------------------------------------------------------------------ escape
def test_escape_off_is_the_paper_algorithm_and_stops_at_the_first_stall():
    checked = 0
    for seed in range(40):
        g = paper_map(seed)
        default = plan(g, PAPER_START, PAPER_GOAL, planner="fusion")
        pure = plan(g, PAPER_START, PAPER_GOAL, planner="fusion", escape=False)
        assert collision_free(g, pure.path)
        if default.info["escapes"] == 0:
            # no stall: the same walk
            np.testing.assert_array_equal(pure.path, default.path)
        else:
            checked += 1
            assert pure.status is Status.LOCAL_MINIMUM
            assert pure.info["escapes"] == 0
    assert checked >= 5


# ------------------------------------------------------------------ rotations and mirrors
@pytest.mark.parametrize("seed", range(12))
def test_step2_is_direction_free(seed):
    # the same global path, rotated with the map: the same walk, rotated
    g = paper_map(seed)
    a = plan(g, PAPER_START, PAPER_GOAL, planner="astar")
    base = follow_path(g, START, GOAL, a.path)
    assert base.path[0].tolist() == list(PAPER_START) and collision_free(g, base.path)
    for turns, mirror in TRANSFORMS:
        tg, tp = transform(g, turns, mirror)
        r = follow_path(tg, tp(START), tp(GOAL), tp(a.path))
        assert r.status is base.status
        assert r.info["escapes"] == base.info["escapes"]
        assert path_length(r.path) == pytest.approx(path_length(base.path), rel=1e-9)
        np.testing.assert_allclose(r.path, tp(base.path), atol=1e-7)


def test_same_success_and_length_on_rotated_maps_with_a_unique_astar_path():
    # A* may break ties between equally short paths differently on a rotated map;
    # on maps where the optimal grid path is unique the whole planner must agree.
    unique = [s for s in range(200)
              if count_shortest_paths(paper_map(s), PAPER_START, PAPER_GOAL) == 1]
    assert len(unique) >= 3
    for seed in unique:
        g = paper_map(seed)
        base = plan(g, PAPER_START, PAPER_GOAL, planner="fusion")
        for turns, mirror in TRANSFORMS:
            tg, tp = transform(g, turns, mirror)
            r = plan(tg, tp(START), tp(GOAL), planner="fusion")
            np.testing.assert_allclose(r.info["astar_path"], tp(base.info["astar_path"]),
                                       atol=1e-9)
            assert r.status is base.status
            assert r.length == pytest.approx(base.length, rel=1e-9)


def test_direction_free_default_works_for_any_direction():
    # the paper-x rule needs the goal towards +x; the default does not
    for turns, mirror in TRANSFORMS:
        for seed in range(10):
            tg, tp = transform(paper_map(seed), turns, mirror)
            r = plan(tg, tp(START), tp(GOAL), planner="fusion")
            assert r.success and collision_free(tg, r.path)


# ------------------------------------------------------------------ parameters
@pytest.mark.parametrize("bad", [
    {"r1_m": 0}, {"r2_m": -1.0}, {"ahead": "forward"}, {"escape": "yes"},
    {"escape_points": 0}, {"k_att": float("inf")}, {"rho0_m": -2.0}, {"step_m": -0.1},
])
def test_bad_params_name_the_value(bad):
    (key, value), = bad.items()
    want = rf"^fusion\.{key}: must be .+, got {re.escape(repr(value))}$"
    with pytest.raises(ConfigError, match=want):
        plan(paper_map(0), PAPER_START, PAPER_GOAL, planner="fusion", **bad)


def test_error_messages_of_the_docs():
    with pytest.raises(ConfigError) as e:
        plan(paper_map(0), PAPER_START, PAPER_GOAL, planner="fusion", ahead="behind")
    assert str(e.value) == "fusion.ahead: must be one of 'progress', 'paper-x', got 'behind'"
    with pytest.raises(ConfigError, match=r"^fusion\.no_such_knob: unknown parameter "
                                          r"\(parameters: .*\br1_m\b.*\)$"):
        plan(paper_map(0), PAPER_START, PAPER_GOAL, planner="fusion", no_such_knob=1)
    # the robot radius is a keyword of plan(), not a parameter of the planner
    with pytest.raises(TypeError):
        FusionParams(robot_radius_m=0.3)


def test_defaults_documented_values():
    p = FusionParams()
    assert (p.k_att, p.k_rep, p.rho0_m) == (40.0, 5.0, 2.0)
    assert p.r1_m == p.r2_m == p.rho0_m and p.ahead == "progress" and p.escape
    # one set of defaults offline and online (the old online r1 1.5 / escape_points 6 are gone)
    assert p.escape_points == 3 and p.stall_steps == 40 and p.heuristic == "euclidean"
    assert p.step_m is None and p.goal_tolerance_m is None and p.stall_distance_m is None
    assert get_planner("fusion").defaults() == dataclasses.asdict(p)
