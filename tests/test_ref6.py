"""Reference method [6]: A* inflection points as sub-goals of an improved (Ge-Cui) APF."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pathfuse import Budget, ConfigError, GridMap, Status, plan
from pathfuse.costmap import costmap_for
from pathfuse.field.forces import repulsive_force
from pathfuse.field.repulsion import grid_improved_repulsion
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.metrics import collision_free, evaluate
from pathfuse.planners.controllers.refs import (
    Ref6Controller,
    Ref6Params,
    improved_repulsive_force,
    improved_repulsive_potential,
    inflection_points,
)
from pathfuse.planners.registry import get_planner
from pathfuse.problem import Problem

START, GOAL = np.array(PAPER_START), np.array(PAPER_GOAL)

# A one-cell-wide S corridor: the only A* path from (1.5, 1.5) to (1.5, 5.5) runs
# right along y = 1.5, up x = 7.5 to y = 3.5, left to x = 1.5, up x = 1.5, and
# right along y = 5.5 (no corner cutting, so no diagonal shortcut at the bends).
S_ROWS = [
    "#########",
    "#.......#",  # y = 5.5 (goal at x = 7.5)
    "#.#######",  # y = 4.5
    "#.......#",  # y = 3.5
    "#######.#",  # y = 2.5
    "#.......#",  # y = 1.5
    "#########",
]
S_START, S_GOAL = (1.5, 1.5), (7.5, 5.5)
S_TURNS = [[7.5, 1.5], [7.5, 3.5], [1.5, 3.5], [1.5, 5.5]]

# A wall at x in [6, 7]; the goal 0.1 m in front of it.  Plain APF (eq. 6) balances
# the attraction about 0.2 m short of the goal with the paper's constants.
WALL_ROWS = ["......#.", "......#.", "......#.", "......#.", "......#."]
WALL_START, WALL_GOAL = (0.5, 2.5), (5.9, 2.5)


def obstacle_centres(g: GridMap) -> np.ndarray:
    return g.cell_to_world(np.argwhere(g.occupied))


def first_visit(path: np.ndarray, point, tol: float) -> int:
    d = np.hypot(*(path - np.asarray(point)).T)
    hits = np.nonzero(d <= tol + 1e-12)[0]
    return int(hits[0]) if hits.size else -1


class GivenPath:
    """A stand-in global plan: the controller reads only its waypoints."""

    def __init__(self, waypoints):
        self.waypoints = np.asarray(waypoints, dtype=np.float64)


def follow_subgoals(g, start, goal, subgoals, params):
    """Step 2 of ref6 alone: the improved APF through ``subgoals`` then the goal.

    The controller takes the inflection points of its global path as sub-goals, so a
    path start -> sub-goals -> goal whose every interior point is a turn gives exactly
    ``subgoals``."""
    wp = np.concatenate([[start], subgoals, [goal]])
    assert inflection_points(wp).tolist() == np.asarray(subgoals, dtype=float).tolist()
    return Ref6Controller(Problem.create(g, start, goal), params, GivenPath(wp)).run(None)


def test_registered():
    spec = get_planner("ref6")
    assert spec.uses_astar and spec.params_cls is Ref6Params
    assert spec.controller is Ref6Controller and spec.offline and spec.online
    assert "robot_radius_m" not in spec.defaults()
    p = Ref6Params()
    assert (p.k_att, p.k_rep, p.rho0_m) == (40.0, 5.0, 2.0)


# ------------------------------------------------------------------ inflection points
def test_inflection_points_hand_values():
    path = [[0, 0], [1, 1], [2, 2], [3, 2], [4, 2], [4, 3], [5, 4]]
    assert inflection_points(path).tolist() == [[2, 2], [4, 2], [4, 3]]
    assert inflection_points([[0, 0], [1, 0], [2, 0], [3, 0]]).shape == (0, 2)
    assert inflection_points([[0, 0], [1, 0]]).shape == (0, 2)
    assert inflection_points([[0, 0]]).shape == (0, 2)
    # repeated points do not count as turns; a reversal does
    assert inflection_points([[0, 0], [1, 0], [1, 0], [2, 0]]).shape == (0, 2)
    assert inflection_points([[0, 0], [2, 0], [1, 0]]).tolist() == [[2, 0]]


MOVES = [(1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1)]


@settings(max_examples=200, deadline=None)
@given(st.lists(st.sampled_from(range(8)), min_size=0, max_size=30),
       st.floats(0.05, 3.0), st.floats(-50, 50), st.floats(-50, 50))
def test_inflection_points_are_the_move_changes(moves, res, x0, y0):
    """Oracle: on a lattice path, a turn is where the integer move changes."""
    cells = [(0, 0)]
    for m in moves:
        cells.append((cells[-1][0] + MOVES[m][0], cells[-1][1] + MOVES[m][1]))
    path = np.array(cells, dtype=float) * res + [x0, y0]
    want = [path[i] for i in range(1, len(moves)) if moves[i - 1] != moves[i]]
    got = inflection_points(path)
    assert got.shape == (len(want), 2)
    np.testing.assert_array_equal(got, np.array(want).reshape(-1, 2))


def test_subgoals_are_exactly_the_astar_inflection_points():
    g = GridMap.from_rows(S_ROWS)
    r = plan(g, S_START, S_GOAL, planner="ref6")
    astar = plan(g, S_START, S_GOAL, planner="astar")
    np.testing.assert_array_equal(r.info["astar_path"], astar.path)
    # the corridor forces the A* path, so its turns are known by hand
    assert r.info["subgoals"][:-1].tolist() == S_TURNS
    np.testing.assert_array_equal(r.info["subgoals"][:-1], inflection_points(astar.path))
    assert r.info["subgoals"][-1].tolist() == list(S_GOAL)
    # ... and the robot visits them in order, within the tolerance, safely
    assert r.success and r.info["subgoals_reached"] == len(S_TURNS) + 1
    tol = r.info["subgoal_tolerance_m"]
    visits = [first_visit(r.path, s, tol) for s in S_TURNS]
    assert all(v > 0 for v in visits) and visits == sorted(visits)
    assert collision_free(g, r.path)
    assert r.path[0].tolist() == list(S_START) and r.path[-1].tolist() == list(S_GOAL)


def test_diagonal_astar_path_turns():
    # an L-shaped obstacle: the A* path goes diagonally, then straight
    g = GridMap.from_rows([
        "........",
        "........",
        "...#####",
        "........",
        "........",
    ])
    r = plan(g, (0.5, 0.5), (7.5, 3.5), planner="ref6")
    np.testing.assert_array_equal(r.info["subgoals"][:-1],
                                  inflection_points(r.info["astar_path"]))
    assert r.info["subgoals"].shape[0] >= 2
    assert r.success and collision_free(g, r.path)


# ------------------------------------------------------------------ the improved repulsion
def _num_grad(f, x, h=1e-6):
    x = np.asarray(x, dtype=float)
    return np.array([(f(x + e) - f(x - e)) / (2 * h) for e in np.eye(2) * h])


@pytest.mark.parametrize("n", [0.5, 1.0, 2.0, 3.0])
@pytest.mark.parametrize("x", [[2.3, 1.4], [3.9, 2.2], [1.2, 3.1]])
def test_improved_force_is_negative_gradient_of_its_potential(n, x):
    obs = [[3.0, 3.0], [1.0, 2.0], [4.0, 1.0]]
    target = [0.7, 0.4]
    f = improved_repulsive_force(x, target, obs, 5.0, 2.0, n, 1.7)
    g = _num_grad(lambda p: improved_repulsive_potential(p, target, obs, 5.0, 2.0, n, 1.7), x)
    np.testing.assert_allclose(f, -g, rtol=1e-5, atol=1e-7)


def test_improved_force_scales_eq6_and_vanishes_at_the_target():
    obs = np.array([[0.0, 0.0]])
    # rho_g = L: the first term is eq. 6 itself
    x, t = np.array([1.0, 0.0]), np.array([1.0, 2.0])
    plain = repulsive_force(x[None], obs, 5.0, 2.0).sum(axis=0)
    f = improved_repulsive_force(x, t, obs, 5.0, 2.0, n=2.0, scale_m=2.0)
    np.testing.assert_allclose(f[0], plain[0])            # along x: only eq. 6
    # along y: n U (rho_g/L)^(n-1)/L towards the target; U = 0.625 at d = 1
    assert f[1] == pytest.approx(2.0 * 0.625 * 1.0 / 2.0)
    assert improved_repulsive_force(t, t, obs).tolist() == [0.0, 0.0]
    # close to the target it is small where eq. 6 is not
    near = np.array([1.0, 1e-3])
    assert np.linalg.norm(improved_repulsive_force(near, [1.0, 0.0], obs)) < 1e-2
    assert np.linalg.norm(repulsive_force(near[None], obs).sum(axis=0)) > 2.0


@pytest.mark.parametrize("n,scale", [(2.0, 2.0), (1.0, 1.0), (0.5, 3.0)])
def test_grid_kernel_matches_brute_force(n, scale):
    g = paper_map(4)
    obs = obstacle_centres(g)
    rng = np.random.default_rng(0)
    pts = rng.uniform(-0.5, 14.5, size=(60, 2))
    cm = costmap_for(g, 0.0, lattice=False)
    assert (cm.ox_m, cm.oy_m, cm.res_m) == (-0.5, -0.5, 1.0)
    for x in pts:
        t = rng.uniform(-0.5, 14.5, size=2)
        want = improved_repulsive_force(x, t, obs, 5.0, 2.0, n, scale)
        got = grid_improved_repulsion(x[0], x[1], t[0], t[1], cm, 5.0, 2.0, n, scale)
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)
    assert grid_improved_repulsion(3.0, 4.0, 3.0, 4.0, cm, 5.0, 2.0, 2.0, 2.0) == (0.0, 0.0)


def test_goal_next_to_obstacle_is_reached_where_plain_apf_stops_short():
    g = GridMap.from_rows(WALL_ROWS)
    apf = plan(g, WALL_START, WALL_GOAL, planner="apf")
    assert apf.status is Status.LOCAL_MINIMUM
    assert math.dist(apf.path[-1], WALL_GOAL) > 0.15   # the equilibrium of eq. 5 and eq. 6
    r = plan(g, WALL_START, WALL_GOAL, planner="ref6")
    assert r.info["subgoals"].tolist() == [list(WALL_GOAL)]   # a straight A* path
    assert r.success and r.path[-1].tolist() == list(WALL_GOAL)
    assert collision_free(g, r.path)


def test_subgoal_next_to_obstacle_is_reached_only_with_subgoal_scaling():
    # the sub-goal lies 0.1 m from the wall; the goal is far away
    g = GridMap.from_rows(["......#.", "......#.", "......#.", "......#.", "......#."])
    sub = [[5.9, 2.5]]
    s, e = np.array([0.5, 2.5]), np.array([0.5, 0.5])
    ok = follow_subgoals(g, s, e, sub, Ref6Params(subgoal_tolerance_m=0.02))
    assert ok.status is Status.SUCCESS and first_visit(ok.path, sub[0], 0.02) > 0
    assert ok.info["subgoals"].tolist() == [*sub, [0.5, 0.5]]
    assert ok.info["subgoals_reached"] == 2 and ok.info["subgoal_tolerance_m"] == 0.02
    assert ok.path[-1].tolist() == [0.5, 0.5] and collision_free(g, ok.path)
    # scaled by the distance to the far goal, the repulsion is not zero at the sub-goal
    bad = follow_subgoals(g, s, e, sub, Ref6Params(subgoal_tolerance_m=0.02, rep_target="goal"))
    assert bad.status is Status.LOCAL_MINIMUM
    assert bad.info["subgoals_reached"] == 0 and first_visit(bad.path, sub[0], 0.02) == -1
    assert bad.path[0].tolist() == [0.5, 2.5] and collision_free(g, bad.path)
    assert "sub-goal 1 of 2" in bad.message


# ------------------------------------------------------------------ paper maps
@pytest.mark.parametrize("seed", range(25))
def test_paper_maps_success_and_safety(seed):
    g = paper_map(seed)
    r = plan(g, PAPER_START, PAPER_GOAL, planner="ref6")
    m = evaluate(g, r)
    assert r.success and m["collision_free"]
    assert r.path[0].tolist() == list(PAPER_START) and r.path[-1].tolist() == list(PAPER_GOAL)
    np.testing.assert_array_equal(r.info["subgoals"][:-1],
                                  inflection_points(r.info["astar_path"]))
    assert r.info["subgoals_reached"] == r.info["subgoals"].shape[0]
    assert r.time_s >= r.info["astar_time_s"] > 0


@pytest.mark.parametrize("seed", range(6))
def test_robot_radius(seed):
    g = paper_map(seed)
    r = plan(g, PAPER_START, PAPER_GOAL, planner="ref6", robot_radius_m=0.3)
    assert collision_free(g, r.path, robot_radius_m=0.3)
    if r.success:
        assert r.path[-1].tolist() == list(PAPER_GOAL)


# ------------------------------------------------------------------ statuses and budgets
def test_unreachable_goal_returns_astar_status():
    g = GridMap.from_rows(["..........", "...#####..", "...#...#..", "...#####..", ".........."])
    r = plan(g, (0.5, 0.5), (5.5, 2.5), planner="ref6")
    assert r.status is Status.NO_PATH and r.path.shape == (0, 2) and "A*" in r.message


def test_iteration_cap():
    g = GridMap(np.zeros((5, 40), dtype=bool))
    r = plan(g, (0.5, 2.5), (38.5, 2.5), planner="ref6", budget=Budget(max_iterations=9))
    assert r.status is Status.MAX_ITERATIONS
    assert r.iterations == 9 and len(r.path) == 10 and collision_free(g, r.path)


def test_time_limit():
    g = GridMap(np.zeros((5, 40), dtype=bool))
    r = plan(g, (0.5, 2.5), (38.5, 2.5), planner="ref6", step_m=1e-4,
             budget=Budget(time_limit_s=1e-6))
    assert r.status is Status.TIMEOUT
    assert 0 < r.iterations < 38 / 1e-4 and len(r.path) == r.iterations + 1


def test_start_at_goal():
    g = GridMap(np.zeros((3, 3), dtype=bool))
    r = plan(g, (1.5, 1.5), (1.5, 1.5), planner="ref6")
    assert r.success and r.path.tolist() == [[1.5, 1.5]]


def test_deterministic():
    g = paper_map(8)
    a = plan(g, PAPER_START, PAPER_GOAL, planner="ref6")
    b = plan(g, PAPER_START, PAPER_GOAL, planner="ref6")
    assert np.array_equal(a.path, b.path)


@pytest.mark.parametrize("bad,name", [
    ({"rep_exponent": 0.0}, "rep_exponent"),
    ({"rep_exponent": float("nan")}, "rep_exponent"),
    ({"rep_scale_m": -1.0}, "rep_scale_m"),
    ({"rep_target": "start"}, "rep_target"),
    ({"subgoal_tolerance_m": 0}, "subgoal_tolerance_m"),
    ({"k_att": -40}, "k_att"),
    ({"stall_steps": 0}, "stall_steps"),
])
def test_bad_params_name_the_value(bad, name):
    g = paper_map(0)
    want = rf"^ref6\.{name}: must be .+, got {re.escape(repr(bad[name]))}$"
    with pytest.raises(ConfigError, match=want):
        plan(g, PAPER_START, PAPER_GOAL, planner="ref6", **bad)


def test_unknown_param_names_the_parameters():
    with pytest.raises(ConfigError, match=r"^ref6\.n: unknown parameter \(parameters: .*"
                                          r"\brep_exponent\b.*\)$"):
        plan(paper_map(0), PAPER_START, PAPER_GOAL, planner="ref6", n=2)
