"""Forces of eq. 3-6 and the grid pieces of the stepping kernels (repulsion, geometry, motion)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pathfuse.costmap import costmap_for, make_costmap
from pathfuse.field import forces
from pathfuse.field.forces import (
    att_force_xy,
    attractive_force,
    attractive_potential,
    rep_force_xy,
    repulsive_force,
    repulsive_potential,
    total_force,
)
from pathfuse.field.motion import HOW_BLOCKED, MARGIN_FRAC, safe_step
from pathfuse.field.repulsion import apf_force, grid_repulsion
from pathfuse.geometry import segment_box_distance, segment_is_clear
from pathfuse.grid import GridMap
from pathfuse.metrics import in_bounds, min_clearance

coord = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)


def _num_grad(f, x, h=1e-6):
    x = np.asarray(x, dtype=float)
    g = np.zeros(2)
    for i in range(2):
        e = np.zeros(2)
        e[i] = h
        g[i] = (f(x + e) - f(x - e)) / (2 * h)
    return g


# ------------------------------------------------------------------ hand-computed values
def test_attraction_hand_values():
    # eq. 3: 1/2 * 40 * (10^2 + 10^2) = 4000; eq. 5: -40 * (X - Xg)
    assert attractive_potential([1, 1], [11, 11], 40.0) == pytest.approx(4000.0)
    assert attractive_force([1, 1], [11, 11], 40.0).tolist() == [400.0, 400.0]
    assert attractive_force([11, 11], [11, 11], 40.0).tolist() == [0.0, 0.0]


def test_repulsion_hand_values():
    # d = 0.5, K_rep = 5, rho0 = 2: U = 2.5 (2 - 0.5)^2 = 5.625, |F| = 5 (2 - 0.5) / 0.25 = 30
    assert repulsive_potential([0.0, 0.5], [0.0, 0.0], 5.0, 2.0) == pytest.approx(5.625)
    np.testing.assert_allclose(repulsive_force([0.0, 0.5], [0.0, 0.0], 5.0, 2.0), [0.0, 30.0])
    # along a diagonal, d = sqrt(2): |F| = 5 (1/sqrt2 - 1/2) / 2, pointing away (+x, +y)
    f = repulsive_force([2.0, 3.0], [1.0, 2.0], 5.0, 2.0)
    mag = 5 * (1 / math.sqrt(2) - 0.5) / 2
    np.testing.assert_allclose(f, [mag / math.sqrt(2)] * 2, rtol=1e-12)
    # zero at and beyond rho0
    assert repulsive_force([2.0, 0.0], [0.0, 0.0], 5.0, 2.0).tolist() == [0.0, 0.0]
    assert repulsive_force([2.5, 0.0], [0.0, 0.0], 5.0, 2.0).tolist() == [0.0, 0.0]
    assert repulsive_potential([2.5, 0.0], [0.0, 0.0], 5.0, 2.0) == 0.0


def test_paper_defaults():
    assert (forces.K_ATT, forces.K_REP, forces.RHO0_M) == (40.0, 5.0, 2.0)


# ------------------------------------------------------------------ forces are -grad U
@pytest.mark.parametrize("x", [[0.3, 0.4], [1.2, -0.7], [-0.1, 1.9], [1.0, 1.0]])
def test_repulsion_is_negative_gradient_of_eq4(x):
    obs = np.array([0.0, 0.0])
    g = _num_grad(lambda p: float(repulsive_potential(p, obs, 5.0, 2.0)), x)
    np.testing.assert_allclose(repulsive_force(x, obs, 5.0, 2.0), -g, rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize("x", [[0.0, 0.0], [3.0, -4.0], [11.0, 10.5]])
def test_attraction_is_negative_gradient_of_eq3(x):
    goal = np.array([11.0, 11.0])
    g = _num_grad(lambda p: float(attractive_potential(p, goal, 40.0)), x, h=1e-4)
    np.testing.assert_allclose(attractive_force(x, goal, 40.0), -g, rtol=1e-6, atol=1e-6)


def test_vectorised_broadcast_over_obstacles():
    obs = np.array([[0.0, 0.0], [1.0, 0.0], [5.0, 5.0]])
    f = repulsive_force(np.array([0.5, 0.5]), obs, 5.0, 2.0)
    assert f.shape == (3, 2)
    assert f[2].tolist() == [0.0, 0.0]
    np.testing.assert_allclose(f[0], f[1] * [-1, 1])  # mirror images about x = 0.5


# ------------------------------------------------------------------ finiteness
@settings(max_examples=300, deadline=None)
@given(coord, coord, coord, coord, st.floats(0.01, 100), st.floats(0.01, 10))
def test_forces_finite_everywhere(x, y, ox_, oy_, k, rho0):
    for f in (
        attractive_force([x, y], [ox_, oy_], k),
        repulsive_force([x, y], [ox_, oy_], k, rho0),
        np.array(att_force_xy(x, y, ox_, oy_, k)),
        np.array(rep_force_xy(x - ox_, y - oy_, k, rho0)),
    ):
        assert np.all(np.isfinite(f))
    assert np.isfinite(repulsive_potential([x, y], [ox_, oy_], k, rho0))
    assert np.isfinite(attractive_potential([x, y], [ox_, oy_], k))


@settings(max_examples=200, deadline=None)
@given(st.floats(-1e-3, 1e-3), st.floats(-1e-3, 1e-3))
def test_repulsion_finite_near_and_at_obstacle(dx, dy):
    f = np.array(rep_force_xy(dx, dy, 5.0, 2.0))
    assert np.all(np.isfinite(f))
    np.testing.assert_allclose(f, repulsive_force([dx, dy], [0.0, 0.0], 5.0, 2.0), rtol=1e-12)
    if dx == 0 and dy == 0:
        assert f.tolist() == [0.0, 0.0]
    else:  # pushes away from the obstacle
        assert f[0] * dx + f[1] * dy > 0


@settings(max_examples=200, deadline=None)
@given(st.floats(-2.5, 2.5), st.floats(-2.5, 2.5))
def test_scalar_kernel_matches_numpy(dx, dy):
    np.testing.assert_allclose(
        rep_force_xy(dx, dy, 5.0, 2.0), repulsive_force([dx, dy], [0.0, 0.0], 5.0, 2.0),
        rtol=1e-12, atol=0,
    )


# ------------------------------------------------------------------ grid window == brute force
def _random_grid(seed, shape=(12, 17), density=0.25, res=1.0, origin=(-0.5, -0.5)):
    rng = np.random.default_rng(seed)
    return GridMap(rng.random(shape) < density, resolution=res, origin=origin)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("res", [1.0, 0.35])
def test_grid_repulsion_equals_sum_over_every_obstacle(seed, res):
    g = _random_grid(seed, res=res, origin=(-0.2, 0.3))
    rng = np.random.default_rng(100 + seed)
    centres = g.cell_to_world(np.argwhere(g.occupied))
    x0, y0, x1, y1 = g.bounds
    goal = np.array([x1 - 0.3, y1 - 0.4])
    for p in np.column_stack([rng.uniform(x0, x1, 40), rng.uniform(y0, y1, 40)]):
        brute = total_force(p, goal, centres, 40.0, 5.0, 2.0)
        fast = apf_force(p[0], p[1], goal[0], goal[1], 40.0, 5.0, 2.0, 2.0,
                         costmap_for(g, 0.0, lattice=False))
        np.testing.assert_allclose(fast, brute, rtol=1e-10, atol=1e-9)


def test_grid_repulsion_radius_truncates():
    # obstacle at distance 1.5: inside rho0 = 2 but outside a sensing radius r2 = 1
    occ = np.zeros((5, 5), dtype=bool)
    occ[2, 4] = True  # centre (4.5, 2.5)
    cm = make_costmap(occ, 0.0, lattice=False)
    full = grid_repulsion(3.0, 2.5, cm, 5.0, 2.0, 2.0)
    cut = grid_repulsion(3.0, 2.5, cm, 5.0, 2.0, 1.0)
    assert full[0] == pytest.approx(-5 * (1 / 1.5 - 0.5) / 1.5**2)
    assert cut == (0.0, 0.0)


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 50), st.floats(-1.0, 16.0), st.floats(-1.0, 16.0))
def test_resultant_force_finite_at_any_point(seed, x, y):
    g = _random_grid(seed, shape=(15, 15), density=0.3)
    # include obstacle centres exactly and points off the map
    cm = make_costmap(g.occupied, 0.0, origin=(-0.5, -0.5), lattice=False)
    f = apf_force(x, y, 11.0, 11.0, 40.0, 5.0, 2.0, 2.0, cm)
    assert np.all(np.isfinite(f))
    c = g.cell_to_world(np.argwhere(g.occupied))[0]
    assert np.all(np.isfinite(apf_force(c[0], c[1], 11.0, 11.0, 40.0, 5.0, 2.0, 2.0, cm)))


# ------------------------------------------------------------------ exact collision test
def test_segment_clear_cases():
    g = GridMap.from_rows([".#", "#."])  # squares [0,1]^2 and [1,2]^2: a diagonal pinch
    occ, (ox, oy), res = g.occupied, g.origin, g.resolution
    c = MARGIN_FRAC
    # the diagonal through the shared corner (1, 1) touches both squares
    assert not segment_is_clear(0.5, 1.5, 1.5, 0.5, occ, ox, oy, res, c)
    assert segment_is_clear(0.2, 1.2, 0.9, 1.8, occ, ox, oy, res, c)
    assert not segment_is_clear(0.5, 1.5, 0.5, 0.5, occ, ox, oy, res, c)  # into a square
    assert not segment_is_clear(0.5, 1.5, 0.5, 2.5, occ, ox, oy, res, c)  # leaves the map
    # a robot of radius 0.3 fits at (0.5, 1.5) but not 0.2 from the square's edge
    assert segment_is_clear(0.5, 1.5, 0.55, 1.5, occ, ox, oy, res, 0.3 + c)
    assert not segment_is_clear(0.5, 1.5, 0.5, 1.2, occ, ox, oy, res, 0.3 + c)


@settings(max_examples=300, deadline=None)
@given(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3),
       st.floats(-1, 1), st.floats(-1, 1), st.floats(0.01, 2), st.floats(0.01, 2))
def test_segment_box_distance_matches_sampling(ax, ay, bx, by, x0, y0, w, h):
    x1, y1 = x0 + w, y0 + h
    d = segment_box_distance(ax, ay, bx, by, x0, y0, x1, y1)
    t = np.linspace(0.0, 1.0, 4001)
    px, py = ax + t * (bx - ax), ay + t * (by - ay)
    dx = np.maximum(np.maximum(x0 - px, 0.0), px - x1)
    dy = np.maximum(np.maximum(y0 - py, 0.0), py - y1)
    sampled = float(np.hypot(dx, dy).min())
    # exact distance <= any sample; samples 1/4000 of the segment apart are within half a gap
    assert d <= sampled + 1e-12
    assert sampled - d <= 0.5 * math.hypot(bx - ax, by - ay) / 4000 + 1e-12
    assert d >= 0.0


@settings(max_examples=400, deadline=None)
@given(st.integers(0, 30), st.floats(-0.5, 7.5), st.floats(-0.5, 7.5), st.floats(-1.5, 1.5),
       st.floats(-1.5, 1.5), st.sampled_from([1e-6, 0.1, 0.3]))
def test_segment_clear_agrees_with_independent_metrics(seed, ax, ay, dx, dy, clear):
    g = _random_grid(seed, shape=(7, 7), density=0.3, origin=(0.0, 0.0))
    seg = np.array([[ax, ay], [ax + dx, ay + dy]])
    got = segment_is_clear(ax, ay, ax + dx, ay + dy, g.occupied, 0.0, 0.0, 1.0, clear)
    x0, y0, x1, y1 = g.bounds
    # the margin (MARGIN_FRAC of a cell) is kept from occupied squares, not from the map's
    # edge: a robot keeps its radius from the edge and may touch it (issue 9)
    edge = max(clear - MARGIN_FRAC * 1.0, 0.0)
    inside = bool(np.all((seg >= [x0 + edge, y0 + edge]) & (seg <= [x1 - edge, y1 - edge])))
    cl = min_clearance(g, seg)
    if abs(cl - clear) < 1e-9:
        return  # on the boundary of the test: either answer is right
    assert got == (inside and in_bounds(g, seg) and cl >= clear)


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 30), st.floats(0, 2 * math.pi), st.floats(0.01, 0.6),
       st.floats(0.0, 0.3))
def test_safe_step_never_collides(seed, angle, step, radius):
    g = _random_grid(seed, shape=(8, 8), density=0.35, origin=(0.0, 0.0))
    clear = radius + MARGIN_FRAC
    rng = np.random.default_rng(seed)
    # a start point that is itself safe
    for _ in range(200):
        x, y = rng.uniform(0, 8, 2)
        if segment_is_clear(x, y, x, y, g.occupied, 0.0, 0.0, 1.0, clear):
            break
    else:
        return
    cm = make_costmap(g.occupied, 0.0, lattice=False)
    nx, ny, how = safe_step(x, y, math.cos(angle), math.sin(angle), step, cm, clear)
    assert math.hypot(nx - x, ny - y) <= step * (1 + 1e-12)
    if how == HOW_BLOCKED:
        assert (nx, ny) == (x, y)
    else:
        seg = np.array([[x, y], [nx, ny]])
        assert min_clearance(g, seg) >= clear - 1e-12
