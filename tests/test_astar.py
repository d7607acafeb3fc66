"""Grid A*: optimal lengths vs MovingAI scenarios and vs an independent Dijkstra oracle,
path validity, statuses, budgets, buffer reuse and determinism."""

from __future__ import annotations

import dataclasses
import gc
import math
import os
import time
import weakref
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.sparse.csgraph import dijkstra

import pathfuse
import pathfuse.search.astar as astar_mod
import pathfuse.search.kernel as kernel_mod
from pathfuse import Budget, ConfigError, GridMap, MapError, QueryError, Status
from pathfuse.io.movingai import read_movingai
from pathfuse.io.scenario import read_scen, scen_map_name
from pathfuse.planners.controllers.follow import AStarParams, FollowController
from pathfuse.planners.params import PursuitParams
from pathfuse.planners.registry import get_planner
from pathfuse.planners.run import warm
from pathfuse.problem import Problem
from pathfuse.search.astar import AStarSearcher, get_searcher

DATA = Path(__file__).parent / "data" / "movingai"
SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "movingai"
SQRT2 = math.sqrt(2.0)

FIXTURES = [
    ("random-32-32-20.map", "random-32-32-20-random-1.scen"),
    ("maze-32-32-2.map", "maze-32-32-2-random-1.scen"),
    ("room-64-64-8.map", "room-64-64-8-random-1.scen"),
    ("den312d.map", "den312d.map.scen"),
    ("Boston_0_256.map", "Boston_0_256.map.scen"),
]


# ----------------------------------------------------------------------------- oracle
def oracle_graph(occ: np.ndarray, corner_cutting: bool) -> scipy.sparse.csr_matrix:
    """8-connected grid graph built cell by cell, independently of pathfuse."""
    h, w = occ.shape
    rows, cols, vals = [], [], []
    for r in range(h):
        for c in range(w):
            if occ[r, c]:
                continue
            for dr in (-1, 0, 1):
                for dc in (-1, 0, 1):
                    if dr == dc == 0:
                        continue
                    rr, cc = r + dr, c + dc
                    if not (0 <= rr < h and 0 <= cc < w) or occ[rr, cc]:
                        continue
                    diagonal = dr != 0 and dc != 0
                    if diagonal and not corner_cutting and (occ[r + dr, c] or occ[r, c + dc]):
                        continue
                    rows.append(r * w + c)
                    cols.append(rr * w + cc)
                    vals.append(SQRT2 if diagonal else 1.0)
    return scipy.sparse.csr_matrix((vals, (rows, cols)), shape=(h * w, h * w))


def check_path(grid: GridMap, path: np.ndarray, start_cell, goal_cell, corner_cutting: bool):
    """Independent validity check of a world-coordinate cell-centre path; returns its length."""
    assert path.ndim == 2 and path.shape[1] == 2 and len(path) >= 1
    cells = grid.world_to_cell(path)
    # every point is exactly a cell centre
    assert np.allclose(grid.cell_to_world(cells), path, atol=1e-12)
    assert tuple(cells[0]) == tuple(start_cell)
    assert tuple(cells[-1]) == tuple(goal_cell)
    assert grid.cells_in_bounds(cells).all()
    assert not grid.occupied[cells[:, 0], cells[:, 1]].any()
    steps = np.diff(cells, axis=0)
    assert (np.abs(steps).max(axis=1, initial=1) == 1).all(), "every step is an 8-neighbour move"
    if not corner_cutting:
        for (r, c), (dr, dc) in zip(cells[:-1], steps, strict=True):
            if dr and dc:
                assert not grid.occupied[r + dr, c] and not grid.occupied[r, c + dc], "corner cut"
    seg = np.hypot(*np.diff(path, axis=0).T) if len(path) > 1 else np.zeros(0)
    return float(seg.sum())


# ----------------------------------------------------------------------------- scenarios
@pytest.fixture(scope="module")
def fixture_problems():
    out = []
    for map_file, scen_file in FIXTURES:
        g = read_movingai(DATA / map_file, resolution=0.5, origin=(3.0, -2.0))
        out.append((g, scen_file, read_scen(DATA / scen_file, g)))
    return out


@pytest.mark.parametrize("heuristic", ["euclidean", "octile"])
def test_fixture_scenarios_every_line(fixture_problems, heuristic):
    n = 0
    for g, scen_file, probs in fixture_problems:
        for p in probs:
            r = pathfuse.plan(g, p.start, p.goal, heuristic=heuristic)
            assert r.status is Status.SUCCESS, (scen_file, p.line, r.message)
            assert r.length == pytest.approx(p.optimal_length, rel=1e-6), (scen_file, p.line)
            n += 1
    assert n == 409 + 333 + 1000 + 290 + 950


def test_fixture_scenario_paths_are_valid(fixture_problems):
    for g, scen_file, probs in fixture_problems:
        for p in probs[::25]:
            r = pathfuse.plan(g, p.start, p.goal)
            length = check_path(g, r.path, p.start_cell, p.goal_cell, corner_cutting=False)
            assert length == pytest.approx(r.length, rel=1e-9), (scen_file, p.line)
            assert np.allclose(r.path[0], p.start) and np.allclose(r.path[-1], p.goal)


def _shared_scen_files() -> list[Path]:
    if not SHARED.is_dir():
        return []
    return sorted(SHARED.glob("*.scen"))  # top level only: terrain_legacy is left out


@pytest.mark.slow
@pytest.mark.skipif(
    not SHARED.is_dir(), reason=f"shared MovingAI data not found at {SHARED}"
)
@pytest.mark.parametrize("scen", _shared_scen_files(), ids=lambda p: p.name)
def test_shared_scenarios_every_line(scen):
    """Every line of every scen file in ../shared/data/movingai (the 512/1024 maps too).

    About 3 minutes on a busy 2-core machine, 2 of them for the 13,720 lines of
    maze512-4-6; ``PATHFUSE_SCEN_EVERY=k`` checks every k-th line only.
    """
    every = int(os.environ.get("PATHFUSE_SCEN_EVERY", "1"))
    map_path = SHARED / Path(scen_map_name(scen)).name
    g = read_movingai(map_path)
    probs = read_scen(scen, g)
    assert probs
    searcher = get_searcher(g)
    for p in probs[::every]:
        r = searcher.search(p.start_cell, p.goal_cell, heuristic="octile")
        assert r.status is Status.SUCCESS, (scen.name, p.line)
        assert r.cost == pytest.approx(p.optimal_length, rel=1e-6), (scen.name, p.line)


# ----------------------------------------------------------------------------- oracle
@st.composite
def grid_queries(draw):
    h = draw(st.integers(1, 14))
    w = draw(st.integers(1, 14))
    density = draw(st.sampled_from([0.0, 0.1, 0.25, 0.4, 0.55]))
    seed = draw(st.integers(0, 2**32 - 1))
    occ = np.random.default_rng(seed).random((h, w)) < density
    free = np.argwhere(~occ)
    if len(free) == 0:
        occ[0, 0] = False
        free = np.argwhere(~occ)
    pairs = [
        (tuple(free[draw(st.integers(0, len(free) - 1))]),
         tuple(free[draw(st.integers(0, len(free) - 1))]))
        for _ in range(3)
    ]
    res = draw(st.sampled_from([1.0, 0.25, 0.05]))
    origin = (draw(st.floats(-50, 50)), draw(st.floats(-50, 50)))
    return occ, pairs, res, origin


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(q=grid_queries(), corner_cutting=st.booleans())
def test_astar_matches_dijkstra_oracle(q, corner_cutting):
    occ, pairs, res, origin = q
    grid = GridMap(occ, resolution=res, origin=origin)
    w = occ.shape[1]
    dist = dijkstra(oracle_graph(occ, corner_cutting), indices=[r * w + c for (r, c), _ in pairs])
    for k, (s, g) in enumerate(pairs):
        want = dist[k, g[0] * w + g[1]]
        start, goal = grid.cell_to_world([s])[0], grid.cell_to_world([g])[0]
        for heuristic in ("euclidean", "octile"):
            r = pathfuse.plan(grid, start, goal, heuristic=heuristic, corner_cutting=corner_cutting)
            if np.isinf(want):
                assert r.status is Status.NO_PATH
                assert r.path.shape == (0, 2) and r.length == 0.0
                continue
            assert r.status is Status.SUCCESS, r.message
            assert r.length == pytest.approx(want * res, rel=1e-9, abs=1e-12)
            length = check_path(grid, r.path, s, g, corner_cutting)
            assert length == pytest.approx(r.length, rel=1e-9, abs=1e-12)
            again = pathfuse.plan(
                grid, start, goal, heuristic=heuristic, corner_cutting=corner_cutting
            )
            assert np.array_equal(again.path, r.path), "same query, same path"


def test_random_start_points_inside_cells_snap_to_centres():
    rng = np.random.default_rng(3)
    occ = rng.random((20, 30)) < 0.2
    occ[0, 0] = occ[19, 29] = False
    g = GridMap(occ, resolution=0.2, origin=(1.0, 1.0))
    # anywhere inside the start/goal cells gives the same path between their centres
    r1 = pathfuse.plan(g, (1.0 + 0.01, 1.0 + 0.19), (1.0 + 29 * 0.2 + 0.15, 1.0 + 19 * 0.2 + 0.05))
    r2 = pathfuse.plan(g, (1.1, 1.1), (1.0 + 29.5 * 0.2, 1.0 + 19.5 * 0.2))
    if r1.status is Status.SUCCESS:
        assert np.array_equal(r1.path, r2.path)
        assert np.allclose(r1.path[0], (1.1, 1.1))
    else:
        assert r1.status is r2.status is Status.NO_PATH


# ----------------------------------------------------------------------------- small cases
def test_corner_rule_on_diagonal_gap():
    g = GridMap.from_rows([".#", "#."])
    a, b = (0.5, 1.5), (1.5, 0.5)  # top-left and bottom-right cells
    assert pathfuse.plan(g, a, b).status is Status.NO_PATH
    assert pathfuse.plan(g, a, b).expansions == 0  # answered from the component labels
    cut = pathfuse.plan(g, a, b, corner_cutting=True)
    assert cut.status is Status.SUCCESS and cut.length == pytest.approx(SQRT2)


def test_no_corner_cutting_goes_around():
    g = GridMap.from_rows(["...", ".#.", "..."])
    r = pathfuse.plan(g, (0.5, 0.5), (2.5, 2.5))
    assert r.length == pytest.approx(4.0)
    assert pathfuse.plan(g, (0.5, 0.5), (2.5, 2.5), corner_cutting=True).length == pytest.approx(
        2 + SQRT2
    )


def test_start_equals_goal_cell():
    g = GridMap.from_rows(["...", "..."], resolution=0.5, origin=(1.0, 1.0))
    r = pathfuse.plan(g, (1.3, 1.2), (1.45, 1.05))
    assert r.status is Status.SUCCESS
    assert r.path.tolist() == [[1.25, 1.25]]
    assert r.length == 0.0


def test_empty_grid_straight_and_diagonal():
    g = GridMap(np.zeros((10, 10), dtype=bool), resolution=0.1)
    r = pathfuse.plan(g, (0.05, 0.05), (0.95, 0.95))
    assert r.length == pytest.approx(9 * SQRT2 * 0.1)
    assert len(r.path) == 10
    r = pathfuse.plan(g, (0.05, 0.05), (0.95, 0.05), heuristic="octile")
    assert r.length == pytest.approx(0.9) and r.expansions == 10


def test_walled_in_goal_is_no_path_without_search():
    # goal enclosed by walls: different component -> NO_PATH without expansions
    g = GridMap.from_rows([".....", ".###.", ".#.#.", ".###.", "....."])
    r = pathfuse.plan(g, (0.5, 0.5), (2.5, 2.5))
    assert r.status is Status.NO_PATH and r.path.shape == (0, 2) and r.expansions == 0
    assert "not reachable" in r.message


# ----------------------------------------------------------------------------- statuses
@pytest.fixture(scope="module")
def den():
    return read_movingai(DATA / "den312d.map")


@pytest.mark.parametrize("heuristic", ["euclidean", "octile"])
def test_max_iterations_boundary(den, heuristic):
    p = read_scen(DATA / "den312d.map.scen", den)[-1]
    full = pathfuse.plan(den, p.start, p.goal, heuristic=heuristic)
    assert full.status is Status.SUCCESS and full.expansions > 10
    exact = pathfuse.plan(den, p.start, p.goal, budget=Budget(max_iterations=full.expansions),
                          heuristic=heuristic)
    assert exact.status is Status.SUCCESS and exact.length == full.length
    short = pathfuse.plan(den, p.start, p.goal, heuristic=heuristic,
                          budget=Budget(max_iterations=full.expansions - 1))
    assert short.status is Status.MAX_ITERATIONS
    assert short.expansions == full.expansions - 1
    assert short.path.shape == (0, 2) and short.length == 0.0
    assert "max_iterations" in short.message


@pytest.mark.parametrize("heuristic", ["euclidean", "octile"])  # ring / radix open list
def test_timeout_and_chunked_resume(den, monkeypatch, heuristic):
    probs = read_scen(DATA / "den312d.map.scen", den)
    p = probs[-1]
    ref = pathfuse.plan(den, p.start, p.goal, budget=Budget(), heuristic=heuristic)
    monkeypatch.setattr(astar_mod, "_CHUNK", 1)
    r = pathfuse.plan(den, p.start, p.goal, budget=Budget(time_limit_s=1e-9), heuristic=heuristic)
    assert r.status is Status.TIMEOUT and r.expansions >= 1 and r.path.shape == (0, 2)
    assert "time_limit_s" in r.message
    # many tiny chunks (kernel stopped and resumed every 3 expansions) give the same search
    monkeypatch.setattr(astar_mod, "_CHUNK", 3)
    for q in probs[::29] + [p]:
        a = pathfuse.plan(den, q.start, q.goal, budget=Budget(time_limit_s=60.0),
                          heuristic=heuristic)
        monkeypatch.setattr(astar_mod, "_CHUNK", 1 << 16)
        b = pathfuse.plan(den, q.start, q.goal, heuristic=heuristic)
        monkeypatch.setattr(astar_mod, "_CHUNK", 3)
        assert a.status is b.status is Status.SUCCESS
        assert np.array_equal(a.path, b.path) and a.expansions == b.expansions
    assert ref.length == pytest.approx(p.optimal_length, rel=1e-9)


def test_bad_queries_through_plan(den):
    free = np.argwhere(~den.occupied)[0]
    blocked = np.argwhere(den.occupied)[0]
    ok = den.cell_to_world([free])[0]
    wall = den.cell_to_world([blocked])[0]
    out = (-5.0, 10.0)
    assert pathfuse.plan(den, out, ok).status is Status.START_OUT_OF_BOUNDS
    assert pathfuse.plan(den, ok, (65.0, 0.5)).status is Status.GOAL_OUT_OF_BOUNDS
    assert pathfuse.plan(den, wall, ok).status is Status.START_OCCUPIED
    assert pathfuse.plan(den, ok, wall).status is Status.GOAL_OCCUPIED
    with pytest.raises(QueryError, match="start"):
        pathfuse.plan(den, (np.nan, 1.0), ok)
    r = pathfuse.plan(den, ok, wall)
    assert r.planner == "astar" and r.path.shape == (0, 2) and "occupied" in r.message
    # the same checks hold for every planner: they live in the problem, checked once
    assert Problem.create(den, ok, wall).failure()[0] is Status.GOAL_OCCUPIED
    assert Problem.create(den, wall, ok).failure()[0] is Status.START_OCCUPIED
    assert Problem.create(den, ok, out).failure()[0] is Status.GOAL_OUT_OF_BOUNDS
    assert Problem.create(den, ok, ok).failure() is None
    with pytest.raises(QueryError, match=r"^goal\[1\]: must be a finite number, got inf"):
        Problem.create(den, ok, (1.0, np.inf))
    with pytest.raises(QueryError, match=r"^goal: must be two numbers \[x, y\], got"):
        pathfuse.plan(den, ok, (1.0, 2.0, 3.0))


def test_params_validation():
    g = GridMap.from_rows(["..", ".."])
    with pytest.raises(ConfigError, match=r"^astar\.heuristic: must be one of 'euclidean', "
                                          r"'octile', got 'manhattan'$"):
        pathfuse.plan(g, (0.5, 0.5), (1.5, 1.5), heuristic="manhattan")
    with pytest.raises(ConfigError,
                       match=r"^astar\.corner_cutting: must be true or false, got 'yes'$"):
        pathfuse.plan(g, (0.5, 0.5), (1.5, 1.5), corner_cutting="yes")
    with pytest.raises(ConfigError, match=r"^astar\.heuristc: unknown parameter "
                                          r"\(parameters: global_planner, heuristic, "
                                          r"corner_cutting, "
                                          r"lookahead_time_s, .*, clear_carrot\)$"):
        pathfuse.plan(g, (0.5, 0.5), (1.5, 1.5), heuristc="octile")
    # the robot radius is a keyword of plan(), not a parameter
    with pytest.raises(ConfigError, match=r"^robot_radius_m: must be a finite number >= 0"):
        pathfuse.plan(g, (0.5, 0.5), (1.5, 1.5), robot_radius_m=-1.0)
    # cell-level A*: bad cells are query errors, a bad heuristic a config error
    with pytest.raises(QueryError, match=r"goal cell \(0, 1\) is occupied"):
        get_searcher(GridMap.from_rows([".#"])).search((0, 0), (0, 1))
    with pytest.raises(QueryError, match=r"goal cell \(2, 0\) is outside the 2x2 grid"):
        get_searcher(g).search((0, 0), (2, 0))
    with pytest.raises(ConfigError, match=r"^heuristic: must be one of 'euclidean', 'octile', "
                                          r"got 'manhattan'$"):
        get_searcher(g).search((0, 0), (1, 1), heuristic="manhattan")
    with pytest.raises(MapError, match="non-empty 2-D"):
        AStarSearcher(np.zeros((0, 3), dtype=bool))


def test_registry_entry():
    spec = get_planner("astar")
    assert spec.controller is FollowController and spec.function is None
    assert spec.params_cls is AStarParams and spec.global_planner == "astar"
    assert spec.uses_astar and spec.offline and spec.online and spec.description
    # the global planner it follows, the search's parameters, then the diff-drive path
    # follower's (planners/controllers/rpp.py)
    assert spec.defaults() == {"global_planner": "astar", "heuristic": "euclidean",
                               "corner_cutting": False, **dataclasses.asdict(PursuitParams())}
    warm(spec)
    # the older name of the same planner
    assert get_planner("astar-follow") is spec
    r = pathfuse.plan(GridMap.from_rows(["..", ".."]), (0.5, 0.5), (1.5, 1.5),
                      planner="astar-follow")
    assert r.success and r.planner == "astar"


def test_result_fields(den):
    p = read_scen(DATA / "den312d.map.scen", den)[100]
    r = pathfuse.plan(den, p.start, p.goal)
    assert r.planner == "astar" and r.time_s > 0 and r.expansions > 0 and r.iterations == 0
    assert r.info["cells"].shape == (len(r.path), 2)
    assert r.info["cost_cells"] * den.resolution == pytest.approx(r.length)
    assert r.to_dict()["status"] == "SUCCESS"


# ----------------------------------------------------------------------------- buffers
def _free_pairs(occ, n, seed):
    free = np.argwhere(~occ)
    rng = np.random.default_rng(seed)
    return [(tuple(free[i]), tuple(free[j])) for i, j in rng.integers(0, len(free), (n, 2))]


@pytest.mark.parametrize("heuristic", ["euclidean", "octile"])  # ring / radix open list
def test_buffer_reuse_generation_wraparound_and_heap_growth(heuristic):
    occ = np.random.default_rng(11).random((60, 70)) < 0.3
    pairs = _free_pairs(occ, 40, 12)
    fresh = [AStarSearcher(occ).search(s, g, heuristic=heuristic) for s, g in pairs]
    reused = AStarSearcher(occ)
    reused._gen = astar_mod._STAMP_LIMIT - 6  # force the stamp reset inside this run
    tiny = AStarSearcher(occ)
    tiny._pack(16, None)  # an open list of 16 entries: must grow
    assert tiny._qkey.shape[0] == tiny._snode.shape[0] == 16
    for (s, g), ref in zip(pairs, fresh, strict=True):
        for searcher in (reused, tiny):
            r = searcher.search(s, g, heuristic=heuristic)
            assert r.status == ref.status
            assert r.cost == ref.cost or (math.isinf(r.cost) and math.isinf(ref.cost))
            assert np.array_equal(r.cells, ref.cells)
    assert reused._gen < 100 and tiny._qkey.shape[0] > 16


def test_searcher_cache_per_map_and_rule():
    g = GridMap(np.zeros((5, 5), dtype=bool))
    a = get_searcher(g)
    assert get_searcher(g) is a
    assert get_searcher(g, corner_cutting=True) is not a
    with a.lock:  # busy (another thread): a fresh searcher is handed out
        b = get_searcher(g)
        assert b is not a and b.search((0, 0), (4, 4)).status is Status.SUCCESS
    assert g in astar_mod._CACHE
    gone = weakref.ref(g)
    del g, a, b
    gc.collect()
    # the cache holds its map weakly: the map and its searchers went
    assert gone() is None
    assert all(k is not None for k in astar_mod._CACHE.keys())


def test_query_time_scales_with_touched_cells_not_map_size():
    big = GridMap(np.zeros((2000, 2000), dtype=bool))
    s = get_searcher(big)
    s.search((0, 0), (1, 1))
    t = time.perf_counter()
    for _ in range(200):
        r = s.search((1000, 1000), (1003, 1004))
    per_query = (time.perf_counter() - t) / 200
    assert r.status is Status.SUCCESS and r.expansions <= 8
    # clearing 4M-cell buffers per query would cost milliseconds; the stamps make it ~us
    assert per_query < 1e-3, per_query


def test_warmup_idempotent():
    astar_mod.warmup()
    t = time.perf_counter()
    astar_mod.warmup()
    assert time.perf_counter() - t < 0.01


def test_small_heap_orders_exactly():
    # the binary heap that orders the current ring bucket (euclidean open list): _spush
    # keeps every parent not greater than its children, ties included ...
    rng = np.random.default_rng(5)
    keys = rng.integers(0, 50, 300).astype(np.uint64)  # many ties
    skey = np.empty(300, dtype=np.uint64)
    snode = np.empty(300, dtype=np.int32)
    size = 0
    for i, k in enumerate(keys):
        size = kernel_mod._spush(skey, snode, size, k, i)
        kids = np.arange(1, size)
        assert np.all(skey[(kids - 1) // 2] <= skey[kids])
    assert sorted(snode[:size].tolist()) == list(range(300))
    assert np.all(keys[snode[:size]] == skey[:size])
    # ... and the kernel pops it (written out in its loop) in order: after any number of
    # expansions, no closed cell has an f above an open cell's (f recomputed from the
    # stored g as the kernel computes it); open grids with a few walls fill the ring's
    # buckets with ties, so the heap holds several entries most of the time
    occ = np.zeros((31, 43), dtype=bool)
    occ[8:20, 14] = occ[22, 5:30] = True
    s = astar_mod.AStarSearcher(occ)
    rows, cols = np.indices(occ.shape)
    for (r0, c0), (r1, c1) in (((2, 2), (28, 40)), ((15, 40), (15, 3)), ((29, 20), (1, 21))):
        h = np.sqrt(((rows - r1) ** 2 + (cols - c1) ** 2).astype(np.float64))
        total = s.search((r0, c0), (r1, c1)).expansions
        assert total > 200
        for k in range(1, total, 7):
            assert s.search((r0, c0), (r1, c1), max_expansions=k).expansions == k
            word = s._cell.reshape(33, 45)[1:-1, 1:-1]
            f = s._g.reshape(33, 45)[1:-1, 1:-1] + h
            closed = s.closed_mask()
            opened = (word != 0xFFFFFFFF) & ((word >> 5) == s._closed_gen - 1)
            assert closed.sum() == k and opened.any()
            assert f[closed].max() <= f[opened].min()


def test_fetch_is_a_hint_that_changes_nothing():
    """The kernel's prefetch (one intrinsic for the six addresses an expansion reads: the
    rows above, at and below a cell, in the cell words and in ``g``) compiles in a numba
    function, returns nothing and leaves both arrays as they were."""
    from numba import njit

    @njit
    def fetch_all(cell, gbuf, uw):
        for q in range(uw, cell.shape[0] - uw):
            kernel_mod._fetch(cell, gbuf, np.uint64(q), np.uint64(uw))
        return cell.sum(), gbuf.sum()

    rng = np.random.default_rng(3)
    cell = rng.integers(0, 2**32, 7 * 9, dtype=np.uint64).astype(np.uint32)
    gbuf = rng.random(7 * 9)
    before = cell.copy(), gbuf.copy()
    fetch_all(cell, gbuf, 9)
    assert np.array_equal(cell, before[0]) and np.array_equal(gbuf, before[1])


def test_ring_left_empty_by_an_ended_query_and_cleared_after_a_stopped_one():
    # the euclidean kernel clears its 4096 ring buckets only when the last query stopped
    # midway (a budget or a time chunk) or the buffers are new; a query that ended (goal
    # closed, region exhausted) empties the buckets it left: the next query must find
    # every bucket empty, and a reused searcher answer as a fresh one, expansion for
    # expansion, whatever came before
    occ = np.random.default_rng(21).random((40, 50)) < 0.3
    occ[:, 25] = True  # two regions: some queries end with NO_PATH
    occ[20, 25] = False
    pairs = _free_pairs(occ, 30, 22)
    reused = AStarSearcher(occ, labels=np.ones(occ.shape, dtype=np.int64))  # no label answer
    assert reused._meta[5] == 0  # new buffers (np.empty): cleared by the first query
    reused._heads[:] = 7
    reused._bits[:] = 12345
    seen = set()
    for i, (s, g) in enumerate(pairs):
        ref = AStarSearcher(occ, labels=np.ones(occ.shape, dtype=np.int64)).search(s, g)
        if i % 3 == 1 and ref.expansions > 2:  # stopped midway: the ring keeps entries
            stop = reused.search(s, g, max_expansions=ref.expansions // 2)
            assert stop.status is Status.MAX_ITERATIONS and reused._meta[5] == 0
        if i % 3 == 2:  # the octile kernel's radix heap has heads of its own: the ring
            # is left as it was (empty after an ended query, to be cleared after a stop)
            ring = reused._meta[5], reused._heads.copy(), reused._bits.copy()
            reused.search(s, g, heuristic="octile")
            assert reused._meta[5] == ring[0]
            assert np.array_equal(reused._heads, ring[1])
            assert np.array_equal(reused._bits, ring[2])
        r = reused.search(s, g)
        seen.add(r.status)
        assert (r.status, r.cost, r.expansions) == (ref.status, ref.cost, ref.expansions)
        assert np.array_equal(r.cells, ref.cells) and np.array_equal(r.points, ref.points)
        if r.expansions:  # a search ran to its end: it left the ring empty
            assert reused._meta[5] == 1
            assert np.all(reused._heads == -1) and not reused._bits.any()
    assert seen >= {Status.SUCCESS, Status.NO_PATH}
