"""Planners at the map's edge (issue 9, item 9).

The map is ``[x0, x1) x [y0, y1)``: a point on the lower or left edge is inside it.  The
edge is not an obstacle: a robot keeps its radius from it (so a point robot may stand and
move on it), while it keeps a sliver more (the margin) from occupied squares.  Every
stepping planner must therefore leave an edge start and reach an edge goal on an empty
map, offline and online, and its path must pass the independent metrics.
"""

from __future__ import annotations

import math

import pytest

import pathfuse
from pathfuse.grid import GridMap
from pathfuse.metrics import collision_free, in_bounds
from pathfuse.planners.registry import planner_names

EMPTY = GridMap.from_rows(["......"] * 3)          # [0, 6) x [0, 3)
PLANNERS = sorted(planner_names())
CELL_PATHS = ("astar", "astar-replan", "jps")  # offline: cell centres, start cell to goal cell


def _check(res, grid, goal, radius=0.0):
    assert res.status is pathfuse.Status.SUCCESS, res.message
    # astar's path is the cell centres from the start cell to the goal cell
    end = grid.cell_to_world(grid.world_to_cell(goal))[0] if res.planner in CELL_PATHS else goal
    assert tuple(res.path[-1]) == pytest.approx(tuple(end), abs=1e-9)
    assert in_bounds(grid, res.path)
    assert collision_free(grid, res.path, radius)


@pytest.mark.parametrize("planner", PLANNERS)
def test_start_on_the_left_edge(planner):
    res = pathfuse.plan(EMPTY, (0.0, 1.5), (5.5, 1.5), planner)
    _check(res, EMPTY, (5.5, 1.5))
    # a straight line (astar: from the start cell's centre, 0.5 m in)
    assert res.length == pytest.approx(5.0 if planner in CELL_PATHS else 5.5, rel=1e-6)


@pytest.mark.parametrize("planner", PLANNERS)
def test_goal_on_the_left_edge(planner):
    res = pathfuse.plan(EMPTY, (5.5, 1.5), (0.0, 1.5), planner)
    _check(res, EMPTY, (0.0, 1.5))
    assert res.length == pytest.approx(5.0 if planner in CELL_PATHS else 5.5, rel=1e-6)


@pytest.mark.parametrize("planner", PLANNERS)
def test_corner_to_corner_along_the_bottom_edge(planner):
    res = pathfuse.plan(EMPTY, (0.0, 0.0), (5.5, 0.0), planner)
    _check(res, EMPTY, (5.5, 0.0))
    if planner == "apf":  # nothing but the goal pulls: straight along the edge
        assert res.length == pytest.approx(5.5, rel=1e-6)


@pytest.mark.parametrize("planner", PLANNERS)
def test_upper_edge_is_outside(planner):
    # [x0, x1): the right and top edges are outside the map
    assert pathfuse.plan(EMPTY, (0.5, 1.5), (6.0, 1.5), planner).status \
        is pathfuse.Status.GOAL_OUT_OF_BOUNDS
    assert pathfuse.plan(EMPTY, (0.5, 3.0), (5.5, 1.5), planner).status \
        is pathfuse.Status.START_OUT_OF_BOUNDS


@pytest.mark.parametrize("planner", PLANNERS)
def test_disc_robot_touching_the_edge(planner):
    # a disc of radius 0.3 whose centre is 0.3 m from the edge touches it: allowed
    g = GridMap.from_rows(["......"] * 3)
    res = pathfuse.plan(g, (0.3, 1.5), (5.5, 1.5), planner, robot_radius_m=0.3)
    _check(res, g, (5.5, 1.5), 0.3)
    # 0.29 m from the edge it overlaps the outside: START_OCCUPIED, as before
    res = pathfuse.plan(g, (0.29, 1.5), (5.5, 1.5), planner, robot_radius_m=0.3)
    assert res.status is pathfuse.Status.START_OCCUPIED


@pytest.mark.parametrize("planner", PLANNERS)
def test_obstacles_keep_their_margin(planner):
    # the margin is still kept from occupied squares: a path along a wall never touches it
    g = GridMap.from_rows(["......", "......", "######"])
    res = pathfuse.plan(g, (0.0, 1.5), (5.5, 1.5), planner)
    assert res.status is pathfuse.Status.SUCCESS, res.message
    assert collision_free(g, res.path)
    ys = res.path[:, 1]
    assert ys.min() > 1.0


@pytest.mark.parametrize("radius", [0.0, 0.2])
@pytest.mark.parametrize("planner", PLANNERS)
def test_online_from_the_edge(planner, radius):
    # a point robot on the edge, or a disc touching it
    sc = {"map": {"rows": ["......"] * 3}, "start": [radius, 1.5], "goal": [5.5, 1.5],
          "robot": {"radius": radius, "max_speed": 1.0}, "time_limit": 30}
    ep = pathfuse.simulate(sc, planner=planner)
    assert ep.status is pathfuse.Status.SUCCESS, ep.message
    assert math.isclose(ep.positions[-1][0], 5.5, abs_tol=0.3)
    assert ep.positions[:, 0].min() >= 0.0
