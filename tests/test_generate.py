"""Seeded random maps and the paper's map."""

from __future__ import annotations

import math
from collections import deque

import networkx as nx
import numpy as np
import pytest

from pathfuse.generate import (
    PAPER_GOAL,
    PAPER_OBSTACLES,
    PAPER_SIZE_M,
    PAPER_START,
    paper_map,
    random_map,
)
from pathfuse.grid import GridMap
from pathfuse.result import ConfigError, MapError

SQ2 = math.sqrt(2.0)


def connected_8_no_corner_cut(occ: np.ndarray, a: tuple[int, int], b: tuple[int, int]) -> bool:
    """Independent BFS: 8 moves, a diagonal needs both orthogonal neighbours free."""
    h, w = occ.shape
    if occ[a] or occ[b]:
        return False
    seen = np.zeros_like(occ)
    seen[a] = True
    q = deque([a])
    while q:
        r, c = q.popleft()
        if (r, c) == b:
            return True
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                nr, nc = r + dr, c + dc
                if (dr or dc) and 0 <= nr < h and 0 <= nc < w and not occ[nr, nc] \
                        and not seen[nr, nc]:
                    if dr and dc and (occ[r + dr, c] or occ[r, c + dc]):
                        continue
                    seen[nr, nc] = True
                    q.append((nr, nc))
    return False


def octile_length(g: GridMap, start, goal) -> float:
    """Oracle: networkx Dijkstra on the no-corner-cut 8-connected graph of cell centres."""
    occ = g.occupied
    h, w = occ.shape
    G = nx.Graph()
    for r in range(h):
        for c in range(w):
            if occ[r, c]:
                continue
            for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):
                nr, nc = r + dr, c + dc
                if not (0 <= nr < h and 0 <= nc < w) or occ[nr, nc]:
                    continue
                if dr and dc and (occ[r + dr, c] or occ[r, c + dc]):
                    continue
                G.add_edge((r, c), (nr, nc), weight=SQ2 if dr and dc else 1.0)
    s = tuple(int(v) for v in g.world_to_cell(start)[0])
    t = tuple(int(v) for v in g.world_to_cell(goal)[0])
    return nx.dijkstra_path_length(G, s, t) * g.resolution


# ----------------------------------------------------------------- paper map
def test_paper_map_setup():
    g = paper_map(0)
    assert g.shape == (15, 15)
    assert g.resolution == 1.0 and g.origin == (-0.5, -0.5)
    assert g.bounds == (-0.5, -0.5, PAPER_SIZE_M - 0.5, PAPER_SIZE_M - 0.5)
    assert int(g.occupied.sum()) == PAPER_OBSTACLES == 50
    # integer world coordinates are cell centres
    centres = g.cell_to_world(np.argwhere(np.ones(g.shape, bool)))
    assert np.array_equal(centres, np.round(centres))
    assert g.cell_to_world(g.world_to_cell([PAPER_START, PAPER_GOAL])).tolist() == [
        [1.0, 1.0], [11.0, 11.0]
    ]


def test_paper_map_deterministic_and_seed_dependent():
    a, b = paper_map(7), paper_map(7)
    assert np.array_equal(a.occupied, b.occupied)
    maps = {paper_map(s).occupied.tobytes() for s in range(20)}
    assert len(maps) == 20


def test_paper_start_goal_free_and_connected_1000_seeds():
    s_cell = (1, 1)
    g_cell = (11, 11)
    for seed in range(1000):
        g = paper_map(seed)
        assert int(g.occupied.sum()) == 50, seed
        assert connected_8_no_corner_cut(g.occupied, s_cell, g_cell), seed
        assert g.is_free([PAPER_START, PAPER_GOAL]).all(), seed


def test_paper_lengths_in_this_frame():
    """The lengths the paper_map docstring states, checked by an independent oracle.

    Empty: 10 diagonals.  A cell touching the diagonal: 9 diagonals + 2 straight
    = 14.7279 (Table I's A* length).  A cell on the diagonal: 8 diagonals + 4 straight.
    """
    def length_with(cells):
        occ = np.zeros((15, 15), bool)
        for rc in cells:
            occ[rc] = True
        return octile_length(GridMap(occ, 1.0, (-0.5, -0.5)), PAPER_START, PAPER_GOAL)

    assert length_with([]) == pytest.approx(10 * SQ2)
    assert length_with([(6, 5)]) == pytest.approx(14.7279, abs=5e-5)
    assert length_with([(6, 5)]) == pytest.approx(9 * SQ2 + 2)
    assert length_with([(6, 6)]) == pytest.approx(8 * SQ2 + 4)


# ----------------------------------------------------------------- random_map
def test_same_seed_same_map_and_exact_count():
    a = random_map((20.0, 10.0), resolution=0.5, obstacles=123, seed=11)
    b = random_map((20.0, 10.0), resolution=0.5, obstacles=123, seed=11)
    c = random_map((20.0, 10.0), resolution=0.5, obstacles=123, seed=12)
    assert a.shape == (20, 40)
    assert np.array_equal(a.occupied, b.occupied)
    assert not np.array_equal(a.occupied, c.occupied)
    assert int(a.occupied.sum()) == int(c.occupied.sum()) == 123


@pytest.mark.parametrize("density, expected", [(0.0, 0), (0.2, 20), (0.255, 26), (1.0, 100)])
def test_density_count(density, expected):
    g = random_map(10.0, density=density, seed=3)
    assert int(g.occupied.sum()) == expected


def test_keep_free_and_connect():
    pts = [(0.5, 0.5), (9.5, 9.5), (4.5, 7.5)]
    for seed in range(50):
        g = random_map(10.0, obstacles=45, seed=seed, keep_free=pts,
                       connect=[((0.5, 0.5), (9.5, 9.5))])
        assert g.is_free(pts).all()
        assert connected_8_no_corner_cut(g.occupied, (0, 0), (9, 9))


def test_resampling_is_deterministic():
    # 5 x 5, 12 obstacles: the corners are often cut apart, so redraws happen
    kw = dict(size_m=5.0, obstacles=12, connect=[((0.5, 0.5), (4.5, 4.5))])
    attempts = []
    for seed in range(30):
        a, b = random_map(seed=seed, **kw), random_map(seed=seed, **kw)
        assert np.array_equal(a.occupied, b.occupied)
        assert connected_8_no_corner_cut(a.occupied, (0, 0), (4, 4))
        attempts.append(a.meta["attempts"])
    assert max(attempts) > 1   # the resampling path was exercised


def test_origin_and_name():
    g = random_map((3.0, 2.0), resolution=1.0, obstacles=0, origin=(5.0, -1.0))
    assert g.bounds == (5.0, -1.0, 8.0, 1.0)
    assert g.name == "random-3x2-n0-s0"
    assert random_map(2.0, obstacles=1, name="x").name == "x"


@pytest.mark.parametrize(
    "kwargs, exc, pattern",
    [
        (dict(), ConfigError, "exactly one of obstacles"),
        (dict(obstacles=3, density=0.1), ConfigError, "exactly one of obstacles"),
        (dict(obstacles=-1), ConfigError, "non-negative integer, got -1"),
        (dict(obstacles=2.5), ConfigError, "non-negative integer, got 2.5"),
        (dict(density=1.5), ConfigError, r"density must be in \[0, 1\], got 1.5"),
        (dict(obstacles=1, seed=-3), ConfigError, "seed must be a non-negative integer"),
        (dict(obstacles=1, seed=1.5), ConfigError, "seed must be a non-negative integer"),
        (dict(obstacles=226), MapError, "cannot place 226 obstacles: .* only 225 cells"),
        (dict(obstacles=224, keep_free=[(1, 1), (2, 2)]), MapError, "only 223 cells"),
        (dict(obstacles=1, size_m=(15.5, 15.0)), MapError, "not a positive whole number"),
        (dict(obstacles=1, resolution=0), MapError, "resolution must be a finite number > 0"),
        (dict(obstacles=1, size_m=-2.0), MapError, "size_m must be finite and > 0"),
        (dict(obstacles=1, keep_free=[(15.5, 1.0)]), MapError, r"keep_free point .* outside"),
        (dict(obstacles=1, connect=[((0, 0),)]), MapError, "pairs of points"),
    ],
)
def test_bad_requests(kwargs, exc, pattern):
    with pytest.raises(exc, match=pattern):
        random_map(**kwargs)


def test_impossible_connection_raises():
    # 3 x 1 corridor, the middle cell must be blocked: ends can never connect
    with pytest.raises(MapError, match="connected after 1 attempts"):
        random_map((3.0, 1.0), obstacles=1, connect=[((0.5, 0.5), (2.5, 0.5))])
    # a 5 x 1 corridor with 2 obstacles among the 3 middle cells: never connected either
    with pytest.raises(MapError, match="after 40 attempts"):
        random_map((5.0, 1.0), obstacles=2, connect=[((0.5, 0.5), (4.5, 0.5))],
                   max_attempts=40)



@pytest.mark.parametrize("small", [1 << 12, 0])  # the flood fill in Python; scipy's labels
def test_label_regions_equal_scipy_labels(monkeypatch, small):
    """The region labels of the generator and of A* equal scipy.ndimage.label's, 4- and
    8-connected, numbering included."""
    from scipy import ndimage

    import pathfuse.grid as grid_mod

    monkeypatch.setattr(grid_mod, "SMALL_LABELS", small)
    monkeypatch.setattr(grid_mod, "_scipy_loaded", lambda: False)  # (imported just above)
    rng = np.random.default_rng(5)
    regions = []
    for _ in range(800):
        h, w = (int(v) for v in rng.integers(1, 20, 2))
        free = rng.random((h, w)) < rng.uniform(0.2, 0.9)
        for eight in (False, True):
            expect, n = ndimage.label(free, structure=np.ones((3, 3), bool) if eight else None)
            got = grid_mod.label_regions(free, eight=eight)
            assert got.dtype == np.int32 and np.array_equal(got, expect), (free, eight)
            regions.append(n)
    assert max(regions) > 10 and min(regions) == 0
