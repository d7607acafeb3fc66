"""The plain APF planner: endings, safety (checked by the independent metrics), budgets."""

from __future__ import annotations

import math
import re
import time

import numpy as np
import pytest

from pathfuse import Budget, ConfigError, GridMap, Status, plan
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.metrics import collision_free, evaluate, path_length
from pathfuse.planners.controllers.apf import APFController, APFParams, force_at
from pathfuse.planners.registry import get_planner
from pathfuse.planners.run import warm


def transform(grid: GridMap, quarter_turns: int, mirror: bool):
    """The map rotated by ``quarter_turns`` x 90 degrees (after an optional x-mirror)
    about its centre, and the matching map of world points.  Square maps only."""
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
    cells = np.argwhere(grid.occupied)
    new = grid.world_to_cell(tp(grid.cell_to_world(cells)))
    occ[new[:, 0], new[:, 1]] = True
    assert occ.sum() == grid.occupied.sum()
    return GridMap(occ, grid.resolution, grid.origin), tp


U_TRAP = GridMap.from_rows([
    "...............",
    ".......G.......",
    "...............",
    "....#######....",
    "....#.....#....",
    "....#.....#....",
    "....#.....#....",
    "...............",
    "...............",
    ".......S.......",
    "...............",
])


def test_registered():
    spec = get_planner("apf")
    assert spec.params_cls is APFParams and not spec.uses_astar
    assert spec.global_planner is None and spec.controller is APFController
    assert spec.offline and spec.online and spec.description
    assert callable(spec.controller.warmup)
    warm(spec)
    # robot_radius_m is part of the problem (a keyword of plan()), not a planner parameter
    assert "robot_radius_m" not in spec.defaults()


def test_open_map_goes_straight():
    g = GridMap(np.zeros((5, 20), dtype=bool))
    r = plan(g, (0.5, 2.5), (18.5, 2.5), planner="apf")
    assert r.status is Status.SUCCESS
    assert r.path[0].tolist() == [0.5, 2.5] and r.path[-1].tolist() == [18.5, 2.5]
    assert r.length == pytest.approx(18.0, abs=1e-9)
    np.testing.assert_allclose(r.path[:, 1], 2.5)
    # default step = 0.1 x resolution; only the last move (onto the goal) may be shorter
    np.testing.assert_allclose(np.diff(r.path[:-1, 0]), 0.1)
    assert 0 < r.path[-1, 0] - r.path[-2, 0] <= 0.1 + 1e-12


@pytest.mark.parametrize("seed", range(40))
def test_paper_maps_safe_and_correct_endpoints(seed):
    g = paper_map(seed)
    r = plan(g, PAPER_START, PAPER_GOAL, planner="apf")
    assert r.status in (Status.SUCCESS, Status.LOCAL_MINIMUM)
    assert r.path[0].tolist() == list(PAPER_START)
    m = evaluate(g, r)
    assert m["collision_free"], (seed, r.message)
    assert r.length == pytest.approx(m["length_m"])
    if r.success:
        assert r.path[-1].tolist() == list(PAPER_GOAL)
        assert math.dist(r.path[-2], PAPER_GOAL) <= r.info["goal_tolerance_m"] + 1e-12
    else:
        assert math.dist(r.path[-1], PAPER_GOAL) > r.info["goal_tolerance_m"]


def test_paper_maps_success_rate():
    # plain APF is a weak planner on 22 % random obstacles; measured 40 % on seeds 0-299
    ok = sum(bool(plan(paper_map(s), PAPER_START, PAPER_GOAL, planner="apf")) for s in range(60))
    assert ok >= 12


def test_u_trap_is_a_local_minimum_found_quickly():
    plan(U_TRAP, (7.5, 1.5), (7.5, 9.5), planner="apf")  # warm
    t = time.perf_counter()
    r = plan(U_TRAP, (7.5, 1.5), (7.5, 9.5), planner="apf")
    assert time.perf_counter() - t < 0.05
    assert r.status is Status.LOCAL_MINIMUM
    assert r.iterations < 300
    x, y = r.path[-1]
    assert 5.0 < x < 10.0 and 4.0 < y < 7.0  # inside the U, below its closed end
    assert collision_free(U_TRAP, r.path)
    assert "local minimum" in r.message or "blocked" in r.message


def test_unreachable_goal():
    g = GridMap.from_rows([
        "..........",
        "...#####..",
        "...#...#..",
        "...#...#..",
        "...#####..",
        "..........",
        "..........",
    ])
    r = plan(g, (0.5, 0.5), (5.5, 4.5), planner="apf")
    assert r.status is Status.LOCAL_MINIMUM
    assert collision_free(g, r.path) and len(r.path) >= 2


def test_iteration_cap():
    g = GridMap(np.zeros((5, 40), dtype=bool))
    r = plan(g, (0.5, 2.5), (38.5, 2.5), planner="apf", budget=Budget(max_iterations=7))
    assert r.status is Status.MAX_ITERATIONS
    assert r.iterations == 7 and len(r.path) == 8
    assert r.path[-1, 0] == pytest.approx(0.5 + 7 * 0.1)


def test_time_limit():
    g = GridMap(np.zeros((5, 40), dtype=bool))
    r = plan(g, (0.5, 2.5), (38.5, 2.5), planner="apf", step_m=1e-4,
             budget=Budget(time_limit_s=1e-6))
    assert r.status is Status.TIMEOUT
    assert 0 < r.iterations < 38 / 1e-4 and len(r.path) == r.iterations + 1


def test_start_at_goal_and_within_tolerance():
    g = GridMap(np.zeros((3, 3), dtype=bool))
    r = plan(g, (1.5, 1.5), (1.5, 1.5), planner="apf")
    assert r.success and r.path.tolist() == [[1.5, 1.5]] and r.length == 0.0
    r = plan(g, (1.5, 1.5), (1.55, 1.5), planner="apf")
    assert r.success and r.path.tolist() == [[1.5, 1.5], [1.55, 1.5]] and r.iterations == 0


def test_goal_tolerance_parameter():
    g = GridMap(np.zeros((3, 12), dtype=bool))
    r = plan(g, (0.5, 1.5), (10.5, 1.5), planner="apf", step_m=0.3, goal_tolerance_m=0.7)
    assert r.success and r.path[-1].tolist() == [10.5, 1.5]
    assert 0 < math.dist(r.path[-2], r.path[-1]) <= 0.7
    assert r.iterations == len(r.path) - 2  # the final move onto the goal is not a step


@pytest.mark.parametrize("seed", range(10))
def test_robot_radius_keeps_clearance(seed):
    g = paper_map(seed)
    r = plan(g, PAPER_START, PAPER_GOAL, planner="apf", robot_radius_m=0.3)
    assert collision_free(g, r.path, robot_radius_m=0.3)


def test_deterministic():
    g = paper_map(5)
    a = plan(g, PAPER_START, PAPER_GOAL, planner="apf")
    b = plan(g, PAPER_START, PAPER_GOAL, planner="apf")
    assert a.status is b.status and np.array_equal(a.path, b.path)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_same_result_on_rotated_and_mirrored_maps(seed):
    g = paper_map(seed)
    base = plan(g, PAPER_START, PAPER_GOAL, planner="apf")
    for turns in range(4):
        for mirror in (False, True):
            if turns == 0 and not mirror:
                continue
            tg, tp = transform(g, turns, mirror)
            r = plan(tg, tp(PAPER_START), tp(PAPER_GOAL), planner="apf")
            assert r.status is base.status
            # the same walk up to float rounding: compare the whole path
            assert r.length == pytest.approx(base.length, rel=1e-9)
            np.testing.assert_allclose(r.path, tp(base.path), atol=1e-7)


def test_force_at_matches_formula():
    g = GridMap.from_rows(["....", "....", "#..."])  # obstacle centre (0.5, 0.5)
    f = force_at(g, (1.5, 0.5), (3.5, 2.5))
    expected = np.array([40 * 2.0 + 5 * (1 - 0.5), 40 * 2.0])
    np.testing.assert_allclose(f, expected)
    assert force_at(g, [[1.5, 0.5], [2.5, 2.5]], (3.5, 2.5)).shape == (2, 2)


@pytest.mark.parametrize("bad", [
    {"k_att": -1}, {"k_att": "forty"}, {"k_att": True}, {"k_rep": -0.5}, {"rho0_m": 0},
    {"step_m": 0.0}, {"step_m": float("nan")}, {"goal_tolerance_m": -1.0},
    {"stall_steps": 0}, {"stall_steps": 2.5}, {"stall_distance_m": 0},
])
def test_bad_params_name_the_value(bad):
    (key, value), = bad.items()
    # one format: KEY: must be WHAT, got VALUE (the key prefixed by the planner's name)
    want = rf"^apf\.{key}: must be .+, got {re.escape(repr(value))}$"
    with pytest.raises(ConfigError, match=want):
        plan(paper_map(0), PAPER_START, PAPER_GOAL, planner="apf", **bad)
    with pytest.raises(ConfigError, match=rf"^{key}: must be .+, got {re.escape(repr(value))}$"):
        APFParams(**bad)


def test_numeric_strings_are_read_as_numbers():
    # the shared validator accepts what YAML 1.1 reads as a string ("1e-2"), normalised
    assert APFParams(k_att="40").k_att == 40.0 and isinstance(APFParams(k_att="40").k_att, float)
    g = GridMap(np.zeros((3, 12), dtype=bool))
    a = plan(g, (0.5, 1.5), (10.5, 1.5), planner="apf", step_m="3e-1")
    b = plan(g, (0.5, 1.5), (10.5, 1.5), planner="apf", step_m=0.3)
    assert a.success and np.array_equal(a.path, b.path) and a.info["step_m"] == 0.3


@pytest.mark.parametrize("radius", [-0.1, float("nan"), float("inf"), "big"])
def test_bad_robot_radius_is_a_problem_error(radius):
    with pytest.raises(ConfigError,
                       match=rf"^robot_radius_m: must be a finite number >= 0, got "
                             rf"{re.escape(repr(radius))}$"):
        plan(paper_map(0), PAPER_START, PAPER_GOAL, planner="apf", robot_radius_m=radius)
    # it is no longer a planner parameter
    with pytest.raises(TypeError):
        APFParams(robot_radius_m=0.3)


def test_info_and_timing():
    g = paper_map(3)
    r = plan(g, PAPER_START, PAPER_GOAL, planner="apf")
    assert r.info["step_m"] == pytest.approx(0.1) and r.info["goal_tolerance_m"] == 0.1
    assert 0 < r.info["step_time_s"] <= r.time_s
    assert r.iterations >= 1 and r.length == pytest.approx(path_length(r.path))
