"""Every registered planner keeps the same contract.

The planners are taken from the registry, so a planner added later is checked
here without editing this file: success and safety on the paper's maps,
correct end points, the statuses of bad queries and exhausted budgets, unknown
parameters, determinism, and the bookkeeping of :class:`PlanResult`.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from pathfuse import Budget, ConfigError, GridMap, Status, plan
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.metrics import evaluate
from pathfuse.planners.registry import get_planner, planner_names

NAMES = planner_names()
SEEDS = range(10)

BOX = GridMap.from_rows([   # the goal (5.5, 2.5) is walled in
    "..........",
    "...#####..",
    "...#...#..",
    "...#####..",
    "..........",
])
CORRIDOR = GridMap(np.zeros((5, 40), dtype=bool))


def check_bookkeeping(r, name):
    assert r.planner == name
    assert math.isfinite(r.time_s) and r.time_s > 0
    assert r.path.ndim == 2 and r.path.shape[1] == 2 and np.all(np.isfinite(r.path))
    if r.path.shape[0] >= 2:
        assert r.length == pytest.approx(float(np.hypot(*np.diff(r.path, axis=0).T).sum()))


def test_all_builtin_planners_are_registered():
    assert {"astar", "apf", "fusion", "ref6", "ref7"} <= set(NAMES)


@pytest.mark.parametrize("name", NAMES)
def test_paper_maps(name):
    spec = get_planner(name)
    wins = 0
    for seed in SEEDS:
        g = paper_map(seed)
        r = plan(g, PAPER_START, PAPER_GOAL, planner=name)
        m = evaluate(g, r)
        check_bookkeeping(r, name)
        assert m["collision_free"], (name, seed)
        # the paper's start and goal are cell centres, so even grid A* starts and ends on them
        assert r.path[0].tolist() == list(PAPER_START), (name, seed)
        if spec.uses_astar:
            # the map connects start and goal: a global planner must get there
            assert r.success, (name, seed, r.message)
        else:
            # a purely local planner may be caught in a local minimum, nothing else
            assert r.status in (Status.SUCCESS, Status.LOCAL_MINIMUM), (name, seed)
        if r.success:
            wins += 1
            assert r.path[-1].tolist() == list(PAPER_GOAL), (name, seed)
    assert wins >= 1


@pytest.mark.parametrize("name", NAMES)
def test_end_points_off_cell_centres(name):
    g = GridMap(np.zeros((8, 12), dtype=bool), resolution=0.5, origin=(-1.0, 2.0))
    s, e = (-0.8, 2.3), (4.6, 5.45)
    r = plan(g, s, e, planner=name)
    assert r.success and evaluate(g, r)["collision_free"]
    if name == "astar":  # a grid path runs between cell centres
        np.testing.assert_allclose(r.path[[0, -1]], [[-0.75, 2.25], [4.75, 5.25]])
    else:
        assert r.path[0].tolist() == list(s) and r.path[-1].tolist() == list(e)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("start,goal,status", [
    ((4.5, 1.5), (0.5, 0.5), Status.START_OCCUPIED),
    ((0.5, 0.5), (4.5, 1.5), Status.GOAL_OCCUPIED),
    ((-0.1, 0.5), (0.5, 0.5), Status.START_OUT_OF_BOUNDS),
    ((0.5, 0.5), (10.0, 0.5), Status.GOAL_OUT_OF_BOUNDS),
    ((0.5, 5.0), (0.5, 0.5), Status.START_OUT_OF_BOUNDS),
])
def test_bad_queries(name, start, goal, status):
    r = plan(BOX, start, goal, planner=name)
    assert r.status is status and r.planner == name
    assert r.path.shape == (0, 2) and not r


@pytest.mark.parametrize("name", NAMES)
def test_unreachable_goal(name):
    spec = get_planner(name)
    if spec.warmup is not None:  # keep a cold numba cache out of the wall-clock check
        spec.warmup()
    t0 = time.perf_counter()
    r = plan(BOX, (0.5, 0.5), (5.5, 2.5), planner=name)
    wall = time.perf_counter() - t0
    check_bookkeeping(r, name)
    assert not r.success
    if spec.uses_astar:
        assert r.status is Status.NO_PATH and r.path.shape == (0, 2)
    else:
        assert r.status in (Status.LOCAL_MINIMUM, Status.NO_PATH)
        assert evaluate(BOX, r)["collision_free"]
    assert wall < 2.0


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("cap", [1, 3])
def test_iteration_cap(name, cap):
    r = plan(CORRIDOR, (0.5, 2.5), (38.5, 2.5), planner=name, budget=Budget(max_iterations=cap))
    check_bookkeeping(r, name)
    assert r.status is Status.MAX_ITERATIONS
    # the cap counts expansions for grid A*, force steps for the potential-field planners
    assert (r.expansions if name == "astar" else r.iterations) == cap
    assert evaluate(CORRIDOR, r)["collision_free"]


@pytest.mark.parametrize("name", NAMES)
def test_unknown_parameter(name):
    with pytest.raises(ConfigError, match="no_such_knob"):
        plan(CORRIDOR, (0.5, 2.5), (38.5, 2.5), planner=name, no_such_knob=1)


@pytest.mark.parametrize("name", NAMES)
def test_defaults_build_and_are_frozen(name):
    spec = get_planner(name)
    p = spec.params_cls()
    field = next(iter(spec.defaults()), None)
    if field is not None:
        with pytest.raises(AttributeError):
            setattr(p, field, getattr(p, field))


@pytest.mark.parametrize("name", NAMES)
def test_deterministic(name):
    g = paper_map(11)
    a = plan(g, PAPER_START, PAPER_GOAL, planner=name)
    b = plan(g, PAPER_START, PAPER_GOAL, planner=name)
    assert a.status is b.status and np.array_equal(a.path, b.path)
    assert a.iterations == b.iterations and a.expansions == b.expansions
