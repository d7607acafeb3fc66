"""Reference method [7]: A* cut into sub-segments, plain APF from segment end to segment end."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pathfuse import Budget, ConfigError, GridMap, Status, plan
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.metrics import collision_free, evaluate
from pathfuse.planners.controllers.refs import Ref7Controller, Ref7Params, segment_ends
from pathfuse.planners.registry import get_planner
from pathfuse.problem import Problem

S_ROWS = [
    "#########",
    "#.......#",
    "#.#######",
    "#.......#",
    "#######.#",
    "#.......#",
    "#########",
]
S_START, S_GOAL = (1.5, 1.5), (7.5, 5.5)


def test_registered():
    spec = get_planner("ref7")
    assert spec.uses_astar and spec.params_cls is Ref7Params
    assert spec.controller is Ref7Controller and spec.offline and spec.online
    assert "robot_radius_m" not in spec.defaults()
    p = Ref7Params()
    assert (p.k_att, p.k_rep, p.rho0_m) == (40.0, 5.0, 2.0)


# ------------------------------------------------------------------ cutting the A* path
def test_segment_ends_hand_values():
    line = [[i, 0] for i in range(7)]
    assert segment_ends(line, segment_points=2).tolist() == [2, 4, 6]
    assert segment_ends(line, segment_points=4).tolist() == [4, 6]
    assert segment_ends(line, segment_points=6).tolist() == [6]
    assert segment_ends(line, segment_points=10).tolist() == [6]
    assert segment_ends(line, segment_length_m=2.0).tolist() == [2, 4, 6]
    assert segment_ends(line, segment_length_m=2.5).tolist() == [3, 6]
    # diagonal steps are sqrt(2) long: the first end at or past 3 m is the 3rd point
    diag = [[i, i] for i in range(8)]
    assert segment_ends(diag, segment_length_m=3.0).tolist() == [3, 6, 7]
    assert segment_ends([[1.0, 1.0]]).tolist() == [0]


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(st.integers(-1, 1), st.integers(-1, 1)).filter(lambda m: m != (0, 0)),
                min_size=1, max_size=40),
       st.floats(0.5, 6.0), st.integers(1, 7))
def test_segment_ends_properties(moves, length, k):
    path = np.cumsum(np.array([(0, 0), *moves], dtype=float), axis=0)
    n = len(path)
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])
    by_len = segment_ends(path, segment_length_m=length)
    assert by_len[-1] == n - 1 and np.all(np.diff(by_len) > 0)
    # every segment but the last is the shortest run of A* moves of at least `length`
    starts = np.concatenate([[0], by_len[:-1]])
    for a, b in zip(starts[:-1], by_len[:-1], strict=True):
        assert cum[b] - cum[a] >= length - 1e-9
        assert cum[b - 1] - cum[a] < length - 1e-9
    # the last segment is shorter than `length` but for its last move
    if n >= 2 and starts[-1] < n - 1:
        assert cum[n - 2] - cum[starts[-1]] < length - 1e-9
    by_k = segment_ends(path, segment_points=k)
    assert by_k.tolist() == [*range(k, n - 1, k), n - 1]


# ------------------------------------------------------------------ joining the local paths
# A segment end is *passed* within subgoal_tolerance_m (like ref6's sub-goals): the robot
# is not moved onto it, the attraction switches to the next end from where it stands.
def first_visits(path, points, tol):
    """Index of the first path point within ``tol`` of each point in turn, each visit at
    or after the previous one (-1 when a point is never passed)."""
    out, k = [], 0
    for p in points:
        d = np.hypot(*(path[k:] - np.asarray(p)).T)
        hits = np.nonzero(d <= tol + 1e-12)[0]
        if hits.size == 0:
            out.append(-1)
            break
        k += int(hits[0])
        out.append(k)
    return out


def _pieces_oracle(g, start, targets, sub_tol):
    """The plain APF planner run independently from each segment end to the next: a piece
    ends at the first point within ``sub_tol`` of its end (the move onto the end that
    plan() appends is dropped), the last piece at the goal."""
    out = [np.asarray(start, dtype=float)[None]]
    pos = np.asarray(start, dtype=float)
    for i, t in enumerate(targets):
        last = i == len(targets) - 1
        r = plan(g, pos, t, planner="apf", goal_tolerance_m=None if last else sub_tol)
        assert r.success
        walk = r.path if last else r.path[: r.iterations + 1]
        out.append(walk[1:])
        pos = walk[-1]
    return np.concatenate(out)


@pytest.mark.parametrize("kw", [{}, {"segment_points": 2}, {"segment_length_m": 1.5},
                                {"segment_points": 1, "subgoal_tolerance_m": 0.2}])
def test_segments_join_without_gaps_or_duplicates(kw):
    g = GridMap.from_rows(S_ROWS)
    r = plan(g, S_START, S_GOAL, planner="ref7", **kw)
    assert r.success, r.message
    assert collision_free(g, r.path)
    assert r.path[0].tolist() == list(S_START) and r.path[-1].tolist() == list(S_GOAL)
    apath, idx, subs = r.info["astar_path"], r.info["segment_index"], r.info["subgoals"]
    # the segment ends are A* points (the last one the goal)
    np.testing.assert_array_equal(subs[:-1], apath[idx[:-1]])
    assert subs[-1].tolist() == list(S_GOAL) and idx[-1] == len(apath) - 1
    np.testing.assert_array_equal(
        idx, segment_ends(apath, kw.get("segment_length_m", 3.0), kw.get("segment_points")))
    # every segment end is passed within the tolerance, in order; then the goal is reached
    tol = r.info["subgoal_tolerance_m"]
    assert tol == kw.get("subgoal_tolerance_m", 0.25 * g.resolution)  # a quarter cell
    visits = first_visits(r.path, subs[:-1], tol)
    assert -1 not in visits and visits == sorted(visits)
    assert r.info["subgoals_reached"] == len(subs)
    # no repeated point, no gap: every move is a force step or the final move onto the goal
    moves = np.hypot(*np.diff(r.path, axis=0).T)
    assert np.all(moves > 0)
    assert np.all(moves[:-1] <= r.info["step_m"] + 1e-9)
    assert moves[-1] <= r.info["goal_tolerance_m"] + 1e-9
    assert len(r.path) - 1 - r.iterations in (0, 1)
    # and the joined path is the plain APF run piece by piece
    oracle = _pieces_oracle(g, S_START, subs, tol)
    np.testing.assert_array_equal(r.path, oracle)
    assert r.length == pytest.approx(float(moves.sum()))


class GivenPath:
    """A stand-in global plan: the controller reads only its waypoints."""

    def __init__(self, waypoints):
        self.waypoints = np.asarray(waypoints, dtype=np.float64)


def test_given_segment_ends_and_info():
    # with segment_points = 1 every waypoint after the start ends a segment
    g = GridMap(np.zeros((4, 6), dtype=bool))
    ends = [[2.5, 3.5], [4.5, 0.5]]
    start, goal = (0.5, 0.5), (5.5, 2.5)
    ctrl = Ref7Controller(Problem.create(g, start, goal), Ref7Params(segment_points=1),
                          GivenPath([start, *ends, goal]))
    r = ctrl.run(None)
    assert r.status is Status.SUCCESS
    assert r.info["subgoals"].tolist() == [*ends, list(goal)]
    assert r.info["segment_index"].tolist() == [1, 2, 3]
    assert r.info["subgoals_reached"] == 3 and r.info["subgoal_tolerance_m"] == 0.25
    visits = first_visits(r.path, ends, 0.25)
    assert -1 not in visits and visits == sorted(visits)
    # the robot is not moved onto a segment end: it turns within the tolerance
    for e in ends:
        assert not np.any(np.all(r.path == e, axis=1))
    # every move is a force step, but for the final move onto the goal
    assert r.path[0].tolist() == list(start) and r.path[-1].tolist() == list(goal)
    assert len(r.path) - 1 - r.steps in (0, 1) and r.steps > 0
    assert collision_free(g, r.path)
    np.testing.assert_array_equal(r.path, _pieces_oracle(g, start, [*ends, goal], 0.25))


# ------------------------------------------------------------------ failures of a local APF
def test_local_minimum_in_a_segment_ends_the_plan_with_the_partial_path():
    # the goal lies 0.1 m in front of a wall: the plain APF of the last segment
    # stops where eq. 5 and eq. 6 balance, about 0.2 m short
    g = GridMap.from_rows(["......#.", "......#.", "......#.", "......#.", "......#."])
    r = plan(g, (0.5, 2.5), (5.9, 2.5), planner="ref7", segment_points=2)
    assert r.status is Status.LOCAL_MINIMUM
    subs = r.info["subgoals"]
    done = r.info["subgoals_reached"]
    assert 1 <= done < subs.shape[0]
    tol = r.info["subgoal_tolerance_m"]
    visits = first_visits(r.path, subs[:done], tol)
    assert -1 not in visits and visits == sorted(visits)
    assert r.path[0].tolist() == [0.5, 2.5] and math.dist(r.path[-1], (5.9, 2.5)) > 0.15
    assert collision_free(g, r.path)
    assert f"sub-goal {done + 1} of {subs.shape[0]}" in r.message


# ------------------------------------------------------------------ paper maps
@pytest.mark.parametrize("seed", range(25))
def test_paper_maps_success_and_safety(seed):
    g = paper_map(seed)
    r = plan(g, PAPER_START, PAPER_GOAL, planner="ref7")
    m = evaluate(g, r)
    assert r.success, r.message
    assert m["collision_free"]
    assert r.path[0].tolist() == list(PAPER_START) and r.path[-1].tolist() == list(PAPER_GOAL)
    subs, idx = r.info["subgoals"], r.info["segment_index"]
    np.testing.assert_array_equal(subs[:-1], r.info["astar_path"][idx[:-1]])
    visits = first_visits(r.path, subs[:-1], r.info["subgoal_tolerance_m"])
    assert -1 not in visits and visits == sorted(visits)
    assert r.info["subgoals_reached"] == subs.shape[0]
    assert r.time_s >= r.info["astar_time_s"] > 0


@pytest.mark.parametrize("seed", range(6))
def test_robot_radius(seed):
    g = paper_map(seed)
    r = plan(g, PAPER_START, PAPER_GOAL, planner="ref7", robot_radius_m=0.3)
    assert r.path[0].tolist() == list(PAPER_START) and len(r.path) >= 2
    assert collision_free(g, r.path, robot_radius_m=0.3)
    if r.success:
        assert r.path[-1].tolist() == list(PAPER_GOAL)


# ------------------------------------------------------------------ statuses and budgets
def test_unreachable_goal_returns_astar_status():
    g = GridMap.from_rows(["..........", "...#####..", "...#...#..", "...#####..", ".........."])
    r = plan(g, (0.5, 0.5), (5.5, 2.5), planner="ref7")
    assert r.status is Status.NO_PATH and r.path.shape == (0, 2) and "A*" in r.message


@pytest.mark.parametrize("cap", [5, 33, 100])
def test_iteration_cap_counts_steps_over_all_segments(cap):
    g = GridMap(np.zeros((5, 40), dtype=bool))
    r = plan(g, (0.5, 2.5), (38.5, 2.5), planner="ref7", budget=Budget(max_iterations=cap))
    assert r.status is Status.MAX_ITERATIONS
    # every move is a force step (segment ends are passed, not snapped onto)
    assert r.iterations == cap and len(r.path) == cap + 1
    assert collision_free(g, r.path)


def test_time_limit():
    g = GridMap(np.zeros((5, 40), dtype=bool))
    r = plan(g, (0.5, 2.5), (38.5, 2.5), planner="ref7", step_m=1e-4,
             budget=Budget(time_limit_s=1e-6))
    assert r.status is Status.TIMEOUT and r.iterations < 38 / 1e-4


def test_start_at_goal():
    g = GridMap(np.zeros((3, 3), dtype=bool))
    r = plan(g, (1.5, 1.5), (1.5, 1.5), planner="ref7")
    assert r.success and r.path.tolist() == [[1.5, 1.5]]


def test_deterministic():
    g = paper_map(8)
    a = plan(g, PAPER_START, PAPER_GOAL, planner="ref7")
    b = plan(g, PAPER_START, PAPER_GOAL, planner="ref7")
    assert np.array_equal(a.path, b.path)


@pytest.mark.parametrize("bad,name", [
    ({"segment_length_m": 0.0}, "segment_length_m"),
    ({"segment_points": 0}, "segment_points"),
    ({"segment_points": 2.5}, "segment_points"),
    ({"subgoal_tolerance_m": -0.1}, "subgoal_tolerance_m"),
    ({"rho0_m": float("inf")}, "rho0_m"),
])
def test_bad_params_name_the_value(bad, name):
    g = paper_map(0)
    want = rf"^ref7\.{name}: must be .+, got {re.escape(repr(bad[name]))}$"
    with pytest.raises(ConfigError, match=want):
        plan(g, PAPER_START, PAPER_GOAL, planner="ref7", **bad)


@pytest.mark.parametrize("name", ["segments", "segment_tolerance_m"])
def test_unknown_params(name):
    # segment_tolerance_m is gone: segment ends share ref6's subgoal_tolerance_m
    with pytest.raises(ConfigError, match=rf"^ref7\.{name}: unknown parameter \(parameters: "
                                          r".*\bsubgoal_tolerance_m\b.*\)$"):
        plan(paper_map(0), PAPER_START, PAPER_GOAL, planner="ref7", **{name: 3})
