"""Repulsion that does not depend on the grid's resolution (``static_repulsion="boundary"``,
ours): the same continuous world rasterised at 0.05, 0.1 and 0.15 m gives the same success,
within 5 points, for every stepping planner; the paper's per-cell sum does not."""

from __future__ import annotations

import numpy as np
import pytest

from pathfuse import GridMap, plan
from pathfuse.costmap import costmap_for, make_costmap
from pathfuse.field.repulsion import boundary_repulsion, grid_repulsion, nearest_obstacle_point
from pathfuse.generate import shapes_map
from pathfuse.geometry import point_box_distance
from pathfuse.metrics import collision_free

SEEDS = range(40)
RESOLUTIONS = (0.05, 0.1, 0.15)
# every length in metres (the defaults of the step and the tolerances are fractions of a cell)
COMMON = {"step_m": 0.05, "goal_tolerance_m": 0.05, "stall_distance_m": 0.125}
EXTRA = {"ref6": {"subgoal_tolerance_m": 0.5}, "ref7": {"subgoal_tolerance_m": 0.25}}


def successes(name, repulsion):
    out = []
    for res in RESOLUTIONS:
        ok = 0
        for s in SEEDS:
            g = shapes_map(s, res)
            r = plan(g, (1.0, 1.0), (11.0, 11.0), planner=name, robot_radius_m=0.2,
                     static_repulsion=repulsion, **COMMON, **EXTRA.get(name, {}))
            assert collision_free(g, r.path, 0.2), (name, s, res)
            ok += r.success
        out.append(100.0 * ok / len(SEEDS))
    return out


@pytest.mark.parametrize("name", ["apf", "fusion", "ref6", "ref7"])
def test_boundary_repulsion_gives_the_same_success_at_every_resolution(name):
    rates = successes(name, "boundary")
    assert max(rates) - min(rates) <= 5.0, (name, rates)


@pytest.mark.parametrize("name", ["apf", "ref6"])
def test_the_papers_per_cell_sum_does_not(name):
    # shown, not wished for: the sum over cell centres grows as the cells shrink
    rates = successes(name, "cells")
    assert max(rates) - min(rates) > 5.0, (name, rates)


def test_nearest_obstacle_point_against_brute_force():
    rng = np.random.default_rng(4)
    g = GridMap(rng.random((20, 25)) < 0.1, resolution=0.2, origin=(-1.0, 0.5))
    occ = np.argwhere(g.occupied)
    ox, oy = g.origin
    for _ in range(300):
        x, y = rng.uniform(-1.0, 4.0), rng.uniform(0.5, 4.5)
        d, px, py = nearest_obstacle_point(x, y, costmap_for(g, 0.0, lattice=False), 1.5)
        want = min(point_box_distance(x, y, ox + c * 0.2, oy + r * 0.2, ox + (c + 1) * 0.2,
                                      oy + (r + 1) * 0.2) for r, c in occ)
        assert d == pytest.approx(min(want, 1.5), abs=1e-12)
        if want < 1.5:
            assert np.hypot(x - px, y - py) == pytest.approx(want, abs=1e-12)


def test_boundary_repulsion_is_the_same_for_a_finely_rasterised_wall_and_matches_the_paper():
    # a wall x >= 3 m at three resolutions: the same force; the per-cell sum grows
    forces, sums = [], []
    for res in RESOLUTIONS:
        n = int(round(6 / res))
        occ = np.zeros((n, n), dtype=bool)
        occ[:, int(round(3 / res)):] = True
        cm = make_costmap(occ, 0.0, resolution_m=res, lattice=False)
        forces.append(boundary_repulsion(2.0, 3.0, cm, 5.0, 2.0, 2.0, 0.5))
        sums.append(grid_repulsion(2.0, 3.0, cm, 5.0, 2.0, 2.0))
    for f in forces:
        assert f == pytest.approx(forces[0], abs=1e-12)
    assert abs(sums[0][0]) > 2.5 * abs(sums[2][0])
    # at the paper's 1 m cells an isolated cell pushes as in the paper along a face normal
    occ = np.zeros((5, 5), dtype=bool)
    occ[2, 3] = True
    cm = make_costmap(occ, 0.0, lattice=False)
    b = boundary_repulsion(2.0, 2.5, cm, 5.0, 2.0, 2.0, 0.5)
    c = grid_repulsion(2.0, 2.5, cm, 5.0, 2.0, 2.0)
    assert b == pytest.approx(c)
