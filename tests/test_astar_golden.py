"""The A* kernel returns, query for query, what the kernel of main at 0a8d90e returned.

Exactness of the cost is checked elsewhere (scenario oracles, a Dijkstra oracle);
this test pins the *path* and the *expansion count* too.  Paths of equal cost
differ only in how ties are broken, and the paper presets' tables depend on the
path A* hands the fusion, so a faster kernel must break ties exactly as before.

For each map and each (heuristic, corner rule), the status, expansions, cost
(``float.hex``) and cells of every query are hashed in order; the digests in
``tests/data/astar_golden.json`` were written by the kernel before it was
rewritten for speed (``python tests/test_astar_golden.py --write`` rewrites
them; only do that when a change of paths is intended).
"""

from __future__ import annotations

import hashlib
import json
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from pathfuse.io.movingai import read_movingai
from pathfuse.io.scenario import read_scen
from pathfuse.search.astar import AStarSearcher

DATA = Path(__file__).parent / "data"
GOLDEN = DATA / "astar_golden.json"
MAPS = [
    ("random-32-32-20.map", "random-32-32-20-random-1.scen"),
    ("maze-32-32-2.map", "maze-32-32-2-random-1.scen"),
    ("room-64-64-8.map", "room-64-64-8-random-1.scen"),
    ("den312d.map", "den312d.map.scen"),
    ("Boston_0_256.map", "Boston_0_256.map.scen"),
]
CONFIGS = [(h, cut) for h in ("euclidean", "octile") for cut in (False, True)]


def _pairs(occ: np.ndarray, n: int, seed: int) -> list[tuple[tuple[int, int], tuple[int, int]]]:
    free = np.argwhere(~occ)
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, len(free), (n, 2))
    return [((int(free[i][0]), int(free[i][1])), (int(free[j][0]), int(free[j][1])))
            for i, j in idx]


def cases() -> Iterator[tuple[str, np.ndarray, list]]:
    """(name, occupancy, queries): the shipped MovingAI maps (scenario lines and random
    pairs, some in different regions) and small synthetic maps full of ties."""
    for map_file, scen_file in MAPS:
        g = read_movingai(DATA / "movingai" / map_file)
        probs = read_scen(DATA / "movingai" / scen_file, g)
        step = max(1, len(probs) // 150)
        queries = [(p.start_cell, p.goal_cell) for p in probs[::step]]
        yield map_file, g.occupied, queries + _pairs(g.occupied, 40, 1)
    empty = np.zeros((17, 23), dtype=bool)
    yield "empty-17x23", empty, _pairs(empty, 60, 2)
    box = np.zeros((40, 40), dtype=bool)
    box[10:30, 18:22] = True
    box[5, :35] = True
    yield "blocks-40x40", box, _pairs(box, 60, 3)
    for seed in range(12):  # paper-sized maps
        occ = np.random.default_rng(100 + seed).random((15, 15)) < 0.3
        yield f"random-15x15-{seed}", occ, _pairs(occ, 12, seed)
    occ = np.random.default_rng(7).random((60, 70)) < 0.35
    yield "random-60x70", occ, _pairs(occ, 60, 4)


def digests() -> dict[str, dict[str, str]]:
    """The digest of every (map, heuristic, corner rule)."""
    out: dict[str, dict[str, str]] = {}
    for name, occ, queries in cases():
        per: dict[str, str] = {}
        for heuristic, cut in CONFIGS:
            s = AStarSearcher(occ, corner_cutting=cut)
            h = hashlib.sha256()
            total = 0
            for a, b in queries:
                r = s.search(a, b, heuristic=heuristic)
                total += r.expansions
                h.update(f"{r.status.name} {r.expansions} {float(r.cost).hex()}|".encode())
                h.update(np.ascontiguousarray(r.cells, dtype=np.int64).tobytes())
            per[f"{heuristic} corner_cutting={cut}"] = f"{h.hexdigest()[:24]} {total}"
        out[name] = per
    return out


def test_paths_and_expansions_match_the_previous_kernel():
    want = json.loads(GOLDEN.read_text())
    got = digests()
    assert sorted(got) == sorted(want)
    bad = [(name, cfg, want[name][cfg], v) for name, per in got.items()
           for cfg, v in per.items() if want[name][cfg] != v]
    assert not bad, bad


@pytest.mark.parametrize("heuristic", ["euclidean", "octile"])
def test_chunked_search_equals_one_run(heuristic, monkeypatch):
    """Resuming the kernel between chunks (a time limit) changes nothing."""
    import pathfuse.search.astar as astar_mod

    g = read_movingai(DATA / "movingai" / "Boston_0_256.map")
    queries = _pairs(g.occupied, 30, 9)
    whole = AStarSearcher(g.occupied)
    ref = [whole.search(a, b, heuristic=heuristic) for a, b in queries]
    monkeypatch.setattr(astar_mod, "_CHUNK", 7)
    chunked = AStarSearcher(g.occupied)
    for (a, b), r0 in zip(queries, ref, strict=True):
        r = chunked.search(a, b, heuristic=heuristic, time_limit_s=60.0)
        assert (r.status, r.expansions, r.cost) == (r0.status, r0.expansions, r0.cost)
        assert np.array_equal(r.cells, r0.cells)


@pytest.mark.parametrize("kind", ["astar", "jps"])
def test_large_map_labels_its_regions_on_first_need(kind):
    """A new map of more than 2**21 cells: the first query pays no labelling; the first
    search that exhausts a region makes the labels, and the next query between two regions
    is answered without a search."""
    from pathfuse import GridMap
    from pathfuse.search.astar import _EAGER_LABELS, get_searcher
    from pathfuse.search.jps import get_jps_searcher

    side = 1500
    assert side * side > _EAGER_LABELS
    occ = np.zeros((side, side), dtype=bool)
    occ[10:13, 10:13] = True
    occ[11, 11] = False  # a walled-in cell
    grid = GridMap(occ)
    s = get_searcher(grid) if kind == "astar" else get_jps_searcher(grid)
    assert s._labels is None and "components" not in vars(grid)
    ok = s.search((0, 0), (5, 7))
    assert ok.status.name == "SUCCESS" and s._labels is None
    first = s.search((11, 11), (0, 0))
    assert first.status.name == "NO_PATH" and first.expansions == 1
    assert s._labels is not None
    again = s.search((0, 0), (11, 11))
    assert again.status.name == "NO_PATH" and again.expansions == 0


if __name__ == "__main__":
    if sys.argv[1:] != ["--write"]:
        sys.exit("usage: python tests/test_astar_golden.py --write")
    GOLDEN.write_text(json.dumps(digests(), indent=1, sort_keys=True) + "\n")
    print(f"wrote {GOLDEN}")
