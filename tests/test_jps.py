"""Jump point search: the same optimal costs as A* on every scenario line and on random
grids, valid 8-connected paths without cut corners, statuses, budgets and buffer reuse."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

from pathfuse import GridMap, QueryError, Status
from pathfuse.io.movingai import read_movingai
from pathfuse.io.scenario import read_scen, scen_map_name
from pathfuse.search.astar import AStarSearcher
from pathfuse.search.jps import JPSSearcher, get_jps_searcher

DATA = Path(__file__).parent / "data" / "movingai"
SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "movingai"


def moves(cells: np.ndarray) -> tuple[int, int]:
    """(straight, diagonal) moves of a cell path: equal for every optimal path."""
    d = np.abs(np.diff(cells, axis=0)).sum(axis=1)
    return int((d == 1).sum()), int((d == 2).sum())


def assert_valid(occ: np.ndarray, cells: np.ndarray, a, b) -> None:
    assert tuple(cells[0]) == tuple(a) and tuple(cells[-1]) == tuple(b)
    assert not occ[cells[:, 0], cells[:, 1]].any()
    steps = np.diff(cells, axis=0)
    assert (np.abs(steps).max(axis=1, initial=1) == 1).all()
    for (r, c), (dr, dc) in zip(cells[:-1], steps, strict=True):
        if dr and dc:
            assert not occ[r + dr, c] and not occ[r, c + dc], "corner cut"


def same_as_astar(occ, queries, astar: AStarSearcher, jps: JPSSearcher) -> int:
    n = 0
    for a, b in queries:
        ra = astar.search(a, b, heuristic="octile")
        rj = jps.search(a, b)
        assert rj.status is ra.status, (a, b)
        if ra.status is Status.SUCCESS:
            assert moves(rj.cells) == moves(ra.cells), (a, b)
            assert rj.cost == pytest.approx(ra.cost, rel=1e-12), (a, b)
            assert_valid(occ, rj.cells, a, b)
            n += 1
    return n


def test_every_fixture_scenario_line():
    n = 0
    for scen in sorted(DATA.glob("*.scen")):
        g = read_movingai(DATA / Path(scen_map_name(scen)).name)
        probs = read_scen(scen, g)
        astar, jps = AStarSearcher(g.occupied), JPSSearcher(g.occupied)
        for p in probs:
            r = jps.search(p.start_cell, p.goal_cell)
            assert r.status is Status.SUCCESS, (scen.name, p.line)
            assert r.cost == pytest.approx(p.optimal_length, rel=1e-9, abs=1e-8), \
                (scen.name, p.line)
        n += same_as_astar(g.occupied, [(p.start_cell, p.goal_cell) for p in probs[::7]],
                           astar, jps)
    assert n > 400


@pytest.mark.slow
@pytest.mark.skipif(not SHARED.is_dir(), reason=f"shared MovingAI data not found at {SHARED}")
@pytest.mark.parametrize("scen", sorted(SHARED.glob("*.scen")) if SHARED.is_dir() else [],
                         ids=lambda p: p.name)
def test_every_shared_scenario_line(scen):
    """Every line of every shipped MovingAI scenario (``PATHFUSE_SCEN_EVERY=k``: every k-th):
    the scenario's optimal length, and the move counts of A*'s path on a sample."""
    every = int(os.environ.get("PATHFUSE_SCEN_EVERY", "1"))
    g = read_movingai(SHARED / Path(scen_map_name(scen)).name)
    probs = read_scen(scen, g)[::every]
    jps = JPSSearcher(g.occupied)
    for p in probs:
        r = jps.search(p.start_cell, p.goal_cell)
        assert r.status is Status.SUCCESS, (scen.name, p.line)
        assert r.cost == pytest.approx(p.optimal_length, rel=1e-9, abs=1e-8), (scen.name, p.line)
    same_as_astar(g.occupied, [(p.start_cell, p.goal_cell) for p in probs[::40]],
                  AStarSearcher(g.occupied), jps)


@pytest.mark.parametrize("density", [0.0, 0.1, 0.25, 0.4, 0.55])
def test_random_grids_match_astar(density):
    rng = np.random.default_rng(int(density * 100))
    for _ in range(8):
        h, w = (int(v) for v in rng.integers(1, 40, 2))
        occ = rng.random((h, w)) < density
        free = np.argwhere(~occ)
        if len(free) == 0:
            continue
        pick = rng.integers(0, len(free), (25, 2))
        queries = [(tuple(free[i]), tuple(free[j])) for i, j in pick]
        same_as_astar(occ, queries, AStarSearcher(occ), JPSSearcher(occ))


def test_corridors_and_rooms_with_doors():
    """Forced neighbours: doors in walls, both sides, all directions."""
    occ = np.zeros((31, 41), dtype=bool)
    occ[10, :] = True
    occ[20, :] = True
    occ[:, 15] = True
    occ[:, 30] = True
    for r, c in ((10, 5), (10, 22), (20, 35), (20, 8), (4, 15), (25, 15), (14, 30), (27, 30)):
        occ[r, c] = False
    free = np.argwhere(~occ)
    rng = np.random.default_rng(3)
    queries = [(tuple(free[i]), tuple(free[j])) for i, j in rng.integers(0, len(free), (150, 2))]
    assert same_as_astar(occ, queries, AStarSearcher(occ), JPSSearcher(occ)) > 100


def test_statuses_budget_and_time_limit():
    occ = np.zeros((30, 30), dtype=bool)
    occ[:, 15] = True
    s = JPSSearcher(occ)
    assert s.search((0, 0), (0, 29)).status is Status.NO_PATH  # labels: no search
    assert s.search((0, 0), (0, 29)).expansions == 0
    r = s.search((3, 4), (3, 4))
    assert r.status is Status.SUCCESS and r.cost == 0.0 and r.cells.tolist() == [[3, 4]]
    occ[29, 15] = False
    s = JPSSearcher(occ)
    full = s.search((0, 0), (0, 29))
    assert full.status is Status.SUCCESS and full.expansions > 2
    cut = s.search((0, 0), (0, 29), max_expansions=1)
    assert cut.status is Status.MAX_ITERATIONS and cut.expansions == 1
    timed = s.search((0, 0), (0, 29), time_limit_s=60.0)
    assert timed.cost == full.cost and np.array_equal(timed.cells, full.cells)
    with pytest.raises(QueryError, match="occupied"):
        s.search((0, 15), (0, 0))
    with pytest.raises(QueryError, match="outside"):
        s.search((0, 0), (30, 0))
    # an enclosed pocket that labels would not catch: walled in on a map with no labels
    pocket = np.zeros((9, 9), dtype=bool)
    pocket[3:6, 3:6] = True
    pocket[4, 4] = False
    labels = np.ones((9, 9), dtype=np.int32)
    r = JPSSearcher(pocket, labels=labels).search((0, 0), (4, 4))
    assert r.status is Status.NO_PATH and r.expansions > 0 and math.isinf(r.cost)


def test_buffer_reuse_stamp_reset_and_heap_growth():
    import pathfuse.search.jps as jps_mod

    occ = np.random.default_rng(8).random((60, 70)) < 0.3
    free = np.argwhere(~occ)
    pick = np.random.default_rng(9).integers(0, len(free), (40, 2))
    queries = [(tuple(free[i]), tuple(free[j])) for i, j in pick]
    fresh = [JPSSearcher(occ).search(a, b) for a, b in queries]
    reused = JPSSearcher(occ)
    reused._gen = jps_mod._STAMP_LIMIT - 6
    reused._hkey = reused._hkey[:2].copy()
    reused._hnode = reused._hnode[:2].copy()
    for (a, b), ref in zip(queries, fresh, strict=True):
        r = reused.search(a, b)
        assert (r.status, r.expansions) == (ref.status, ref.expansions)
        assert np.array_equal(r.cells, ref.cells)
    assert reused._gen < 100 and reused._hkey.shape[0] > 2


def test_cached_per_map_and_world_points():
    g = GridMap.from_rows(["......", ".##...", "......"], resolution=0.5, origin=(1.0, 2.0))
    s = get_jps_searcher(g)
    assert get_jps_searcher(g) is s
    r = s.search_checked((0, 0), (2, 5), "octile", None, None, (1.0, 2.0, 0.5))
    assert r.status is Status.SUCCESS
    assert np.allclose(r.points, g.cell_to_world(r.cells))
    with s.lock:
        assert get_jps_searcher(g) is not s
