"""Any-angle planners and the true shortest path, against independent checks.

* :func:`line_of_sight` answers what :func:`segment_is_clear` answers.
* ``thetastar``, ``lazy-thetastar`` and ``astar-smooth`` paths are collision-free by
  :mod:`pathfuse.metrics`, never shorter than ``shortest`` and (for a point robot between
  cell centres) never longer than A*'s.
* ``shortest`` is checked against a brute force written separately: every grid point a
  candidate corner, every pair of points joined when the segment is admissible under the
  grazing rule of the limit (exact rational arithmetic: it may touch squares, not enter one,
  not run between two squares sharing an edge, not pass through a point where two squares
  meet only at a corner), and networkx's Dijkstra over that graph.
"""

from __future__ import annotations

import itertools
import math
from fractions import Fraction

import networkx as nx
import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from pathfuse import GridMap, Status, plan
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.geometry import MARGIN_FRAC, segment_is_clear
from pathfuse.metrics import collision_free, evaluate, path_length, segment_clearances
from pathfuse.search.los import line_of_sight, smooth_path
from pathfuse.search.visibility import growth_cells, shortest_path

ANY = ("thetastar", "lazy-thetastar", "astar-smooth")


@st.composite
def grids(draw, max_side=9):
    h = draw(st.integers(2, max_side))
    w = draw(st.integers(2, max_side))
    density = draw(st.sampled_from([0.0, 0.15, 0.3, 0.45]))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    occ = rng.random((h, w)) < density
    free = np.argwhere(~occ)
    if len(free) < 2:
        occ[0, 0] = occ[-1, -1] = False
        free = np.argwhere(~occ)
    a = tuple(free[draw(st.integers(0, len(free) - 1))])
    b = tuple(free[draw(st.integers(0, len(free) - 1))])
    return occ, a, b


# ----------------------------------------------------------------------------- line of sight
@settings(max_examples=300, deadline=None)
@given(grids(), st.lists(st.floats(-0.5, 10.5), min_size=4, max_size=4),
       st.sampled_from([0.0, 1e-6, 0.2, 0.5, 1.3]), st.sampled_from([1.0, 0.25]))
def test_line_of_sight_equals_segment_is_clear(g, xy, clear, res):
    occ = g[0]
    ax, ay, bx, by = (v * res for v in xy)
    want = segment_is_clear(ax, ay, bx, by, occ, -0.3, 0.2, res, clear * res)
    got = line_of_sight(ax, ay, bx, by, occ, -0.3, 0.2, res, clear * res)
    assert got == want


_TIE = np.zeros((7, 7), dtype=bool)  # square (6, 3) lies exactly at the clearance of B
_TIE[1, 0] = _TIE[2, 1] = _TIE[2, 4] = _TIE[6, 3] = True


@settings(max_examples=300, deadline=None)
@given(grids(), st.lists(st.integers(0, 20), min_size=4, max_size=4),
       st.sampled_from([0.0, 1e-6, 0.5, 1.0]), st.sampled_from([1.0, 0.05, 0.1]))
@example((_TIE, (0, 0), (0, 0)), [12, 5, 9, 12], 0.5, 0.05)  # both scans must see that square
def test_line_of_sight_on_grid_aligned_segments(g, xy, clear, res):
    # end points on cell corners and centres: segments along grid lines and through corners
    occ = g[0]
    ax, ay, bx, by = (v * 0.5 * res for v in xy)
    want = segment_is_clear(ax, ay, bx, by, occ, 0.0, 0.0, res, clear * res)
    assert line_of_sight(ax, ay, bx, by, occ, 0.0, 0.0, res, clear * res) == want


def _clear_by_metrics(occ, ox, oy, res, ax, ay, bx, by, clear):
    """An independent answer: the exact clearance of pathfuse.metrics (its own kernels) from
    every occupied square, and the edge rule; None when it is within rounding of ``clear``."""
    h, w = occ.shape
    edge = max(clear - MARGIN_FRAC * res, 0.0)
    x0, y0, x1, y1 = ox + edge, oy + edge, ox + w * res - edge, oy + h * res - edge
    if not all(x0 <= x <= x1 for x in (ax, bx)) or not all(y0 <= y <= y1 for y in (ay, by)):
        return False
    g = GridMap(occ, res, (ox, oy))
    d = float(segment_clearances(g, [[ax, ay], [bx, by]])[0])
    if abs(d - clear) < 1e-9 * max(1.0, res):
        return None
    return d >= clear


def test_long_segments_against_an_independent_clearance():
    # long oblique segments take the strip scan in segment_is_clear (and line_of_sight
    # always does): both against the metrics' exact clearance, which scans differently
    rng = np.random.default_rng(0)
    checked = 0
    for occ in (rng.random((200, 300)) < 0.02, rng.random((60, 90)) < 0.2):
        h, w = occ.shape
        for _ in range(300):
            ax, bx = rng.uniform(0, w, 2)
            ay, by = rng.uniform(0, h, 2)
            for clear in (1e-6, 0.7):
                want = _clear_by_metrics(occ, 0.0, 0.0, 1.0, ax, ay, bx, by, clear)
                if want is None:
                    continue
                assert segment_is_clear(ax, ay, bx, by, occ, 0.0, 0.0, 1.0, clear) == want
                assert line_of_sight(ax, ay, bx, by, occ, 0.0, 0.0, 1.0, clear) == want
                checked += 1
    assert checked > 1000


@settings(max_examples=300, deadline=None)
@given(grids(max_side=40), st.lists(st.floats(0.0, 1.0), min_size=4, max_size=4),
       st.sampled_from([0.0, 1e-6, 0.3, 1.3]), st.sampled_from([1.0, 0.05]))
def test_segment_is_clear_against_an_independent_clearance(g, uv, clear, res):
    occ = g[0]
    h, w = occ.shape
    ax, bx = uv[0] * w * res - 0.3, uv[1] * w * res - 0.3
    ay, by = uv[2] * h * res + 0.2, uv[3] * h * res + 0.2
    want = _clear_by_metrics(occ, -0.3, 0.2, res, ax, ay, bx, by, clear * res)
    if clear == 0.0 or want is None:  # a point touching a square: the metrics' own rule
        return
    assert segment_is_clear(ax, ay, bx, by, occ, -0.3, 0.2, res, clear * res) == want
    assert line_of_sight(ax, ay, bx, by, occ, -0.3, 0.2, res, clear * res) == want


def test_smooth_path_keeps_sight_and_shortens():
    occ = np.zeros((5, 5), dtype=bool)
    occ[2, 1:4] = True
    pts = np.array([[0.5, 0.5], [1.5, 0.5], [2.5, 0.5], [3.5, 0.5], [4.5, 1.5], [4.5, 2.5],
                    [4.5, 3.5], [3.5, 4.5], [2.5, 4.5]])
    out = smooth_path(pts, occ, 0.0, 0.0, 1.0, 1e-6)
    assert out[0].tolist() == [0.5, 0.5] and out[-1].tolist() == [2.5, 4.5]
    assert path_length(out) < path_length(pts)
    for a, b in itertools.pairwise(out):
        assert segment_is_clear(*a, *b, occ, 0.0, 0.0, 1.0, 1e-6)


# ----------------------------------------------------------------------------- brute force
def _cell_free(occ, r, c):
    h, w = occ.shape
    return 0 <= r < h and 0 <= c < w and not occ[r, c]


def _admissible(occ, a, b):
    """The grazing rule in exact arithmetic (cell units, origin 0)."""
    ax, ay = a
    bx, by = b
    dx, dy = bx - ax, by - ay
    ts = {Fraction(0), Fraction(1)}
    for k in range(math.floor(min(ax, bx)), math.ceil(max(ax, bx)) + 1):
        if dx != 0 and min(ax, bx) < k < max(ax, bx):
            ts.add((k - ax) / dx)
    for k in range(math.floor(min(ay, by)), math.ceil(max(ay, by)) + 1):
        if dy != 0 and min(ay, by) < k < max(ay, by):
            ts.add((k - ay) / dy)
    ts = sorted(ts)
    for t0, t1 in itertools.pairwise(ts):
        m = (t0 + t1) / 2
        x, y = ax + m * dx, ay + m * dy
        if x.denominator == 1:      # running along a vertical grid line
            c = int(x)
            r = math.floor(y)
            if not (_cell_free(occ, r, c - 1) or _cell_free(occ, r, c)):
                return False
        elif y.denominator == 1:    # along a horizontal grid line
            r = int(y)
            c = math.floor(x)
            if not (_cell_free(occ, r - 1, c) or _cell_free(occ, r, c)):
                return False
        elif not _cell_free(occ, math.floor(y), math.floor(x)):
            return False
    for t in ts[1:-1]:              # through a grid point where two squares meet at a corner
        x, y = ax + t * dx, ay + t * dy
        if x.denominator == 1 and y.denominator == 1 and _pinch(occ, int(y), int(x)):
            return False
    return True


def _pinch(occ, r, c):
    """Whether two squares meet only at the grid point (c, r) (the other two cells free)."""
    ll, lr = not _cell_free(occ, r - 1, c - 1), not _cell_free(occ, r - 1, c)
    ul, ur = not _cell_free(occ, r, c - 1), not _cell_free(occ, r, c)
    return (ll and ur and not lr and not ul) or (lr and ul and not ll and not ur)


def brute_force_shortest(occ, start, goal):
    """Dijkstra over every grid point plus start and goal (cell units), grazing allowed.

    A path may touch a grid point, but not one where two squares meet only at a corner
    (it would pass between them)."""
    h, w = occ.shape
    pts = [(Fraction(start[0]), Fraction(start[1])), (Fraction(goal[0]), Fraction(goal[1]))]
    for i in range(h + 1):
        for j in range(w + 1):
            if any(_cell_free(occ, i + di, j + dj) for di in (-1, 0) for dj in (-1, 0)) \
                    and not _pinch(occ, i, j):
                pts.append((Fraction(j), Fraction(i)))
    graph = nx.Graph()
    for u, v in itertools.combinations(range(len(pts)), 2):
        if _admissible(occ, pts[u], pts[v]):
            graph.add_edge(u, v, weight=math.dist(pts[u], pts[v]))
    try:
        return nx.dijkstra_path_length(graph, 0, 1)
    except (nx.NetworkXNoPath, nx.NodeNotFound):
        return math.inf


def test_brute_force_rules_by_hand():
    occ = np.array([[True, False], [False, True]])  # squares meeting at the corner (1, 1)
    f = Fraction
    assert not _admissible(occ, (f(1, 2), f(3, 2)), (f(3, 2), f(1, 2)))   # through the pinch
    assert _admissible(occ, (f(1), f(1, 2)), (f(1), f(1, 2)))             # a point
    assert _admissible(occ, (f(1, 2), f(3, 2)), (f(1), f(1)))             # to the corner
    occ = np.array([[False, False, False], [False, True, False], [False, False, False]])
    assert _admissible(occ, (f(0), f(0)), (f(3), f(3))) is False          # through the square
    assert _admissible(occ, (f(0), f(1)), (f(3), f(1)))                   # along its edge
    assert _admissible(occ, (f(0), f(0)), (f(2), f(1)))                   # touches (2, 1)
    occ = np.array([[True, True]])
    assert not _admissible(occ, (f(0), f(1, 2)), (f(2), f(1, 2)))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(grids(max_side=6))
def test_shortest_matches_the_brute_force(g):
    occ, a, b = g
    start = (a[1] + 0.5, a[0] + 0.5)
    goal = (b[1] + 0.5, b[0] + 0.5)
    want = brute_force_shortest(occ, start, goal)
    r = shortest_path(occ, 0.0, 0.0, 1.0, 0.0, start, goal)
    if math.isinf(want):
        assert r.status is Status.NO_PATH
        return
    assert r.status is Status.SUCCESS
    rho = growth_cells(0.0, 1.0)
    assert want - 1e-12 <= r.length <= want + 3 * rho * (len(r.points) + 1)
    assert r.length == pytest.approx(path_length(r.points), abs=1e-12)
    assert collision_free(GridMap(occ), r.points)


def test_shortest_by_hand():
    # around one square: the path bends at its corner, 5e-7 cells off
    g = GridMap.from_rows(["...", ".#.", "..."])
    r = plan(g, (0.5, 0.5), (2.5, 2.5), planner="shortest")
    assert r.success and r.path.shape == (3, 2)
    assert r.length == pytest.approx(2 * math.hypot(1.5, 0.5), abs=3e-6)
    assert evaluate(g, r)["collision_free"]
    # two squares meeting at a corner: no passing between them
    g = GridMap.from_rows(["...#", "..#.", "...."])
    r = plan(g, (3.5, 1.5), (1.5, 2.5), planner="shortest")
    assert r.success and r.length > math.hypot(2, 1) + 0.5
    # walled in: no path
    g = GridMap.from_rows([".#.", "#..", "..."])
    assert plan(g, (0.5, 2.5), (2.5, 0.5), planner="shortest").status is Status.NO_PATH


# ----------------------------------------------------------------------------- any-angle
@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(grids(max_side=12), st.sampled_from([1.0, 0.5]))
def test_any_angle_paths_between_shortest_and_astar(g, res):
    occ, a, b = g
    grid = GridMap(occ, resolution=res, origin=(-1.0, 2.0))
    start, goal = grid.cell_to_world(np.array([a, b]))
    ref = plan(grid, start, goal, planner="astar")
    low = plan(grid, start, goal, planner="shortest")
    assert ref.status is low.status
    for name in ANY:
        r = plan(grid, start, goal, planner=name)
        assert r.status is ref.status, name
        if not r.success:
            continue
        assert evaluate(grid, r)["collision_free"], name
        assert r.path[0].tolist() == list(start) and r.path[-1].tolist() == list(goal)
        assert low.length - 1e-9 <= r.length <= ref.length + 1e-9, (name, low.length, ref.length)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(grids(max_side=10), st.sampled_from([0.2, 0.35, 0.6]))
def test_disc_robot_paths_keep_the_radius(g, radius):
    occ, a, b = g
    grid = GridMap(occ)
    start, goal = grid.cell_to_world(np.array([a, b]))
    for name in (*ANY, "shortest"):
        r = plan(grid, start, goal, planner=name, robot_radius_m=radius)
        if r.success:
            assert collision_free(grid, r.path, robot_radius_m=radius), name
            x0, y0, x1, y1 = grid.bounds
            assert r.path[:, 0].min() - x0 >= radius and x1 - r.path[:, 0].max() >= radius


def test_paper_maps_order_of_lengths():
    for seed in range(30):
        g = paper_map(seed)
        lengths = {n: plan(g, PAPER_START, PAPER_GOAL, planner=n).length
                   for n in ("shortest", "thetastar", "lazy-thetastar", "astar-smooth", "astar")}
        for n in ANY:
            assert lengths["shortest"] - 1e-9 <= lengths[n] <= lengths["astar"] + 1e-9, (seed, n)


def test_margin_is_pathfuse_margin():
    # every pathfuse move keeps MARGIN_FRAC cells; the shortest path keeps half of it
    assert growth_cells(0.0, 0.05) == pytest.approx(0.5 * MARGIN_FRAC)
    g = paper_map(3)
    r = plan(g, PAPER_START, PAPER_GOAL, planner="shortest")
    m = evaluate(g, r)
    assert m["collision_free"] and 0 < m["min_clearance_m"] < 1e-6


def test_budget_and_time_limit():
    from pathfuse import Budget

    g = paper_map(1)
    for name in (*ANY, "shortest"):
        r = plan(g, PAPER_START, PAPER_GOAL, planner=name, budget=Budget(max_iterations=2))
        assert r.status is Status.MAX_ITERATIONS and r.expansions == 2, name
        r = plan(g, PAPER_START, PAPER_GOAL, planner=name, budget=Budget(time_limit_s=5.0))
        assert r.success, name


def test_upper_bound_never_changes_the_answer():
    for seed in range(20):
        g = paper_map(seed)
        args = (g.occupied, *g.origin, g.resolution, 0.0, PAPER_START, PAPER_GOAL)
        free = shortest_path(*args)
        astar = plan(g, PAPER_START, PAPER_GOAL).length
        for bound in (astar, free.length, 0.5 * free.length, 1e9):
            r = shortest_path(*args, upper_bound_m=bound)
            assert r.status is Status.SUCCESS
            np.testing.assert_array_equal(r.points, free.points)
            assert r.length == free.length
