"""The expansion order of the A* closed set (the page's animated search).

``AStarSearcher.expansion_order`` sorts the closed cells by the ``f`` the kernel
popped them at.  The check here does not trust that argument: it stops the same
search after k expansions (``max_expansions=k``) and compares the cells closed
then with the first k cells of the order.  They may differ only by cells whose
``f`` ties with the k-th cell's (the kernel orders ties its own way).
"""

from __future__ import annotations

import base64
import math

import numpy as np
import pytest

from pathfuse.generate import paper_map, random_map
from pathfuse.io import load_map
from pathfuse.problem import Problem
from pathfuse.search.astar import AStarSearcher
from pathfuse.web.layers import closed_order, closed_set
from pathfuse.web.maps import Limits, MapStore, pack_mask
from pathfuse.web.service import plan_request

BOSTON = "tests/data/movingai/Boston_0_256.map"


def check_prefixes(occ, start, goal, heuristic, cutting, ks):
    s = AStarSearcher(occ, corner_cutting=cutting)
    full = s.search(start, goal, heuristic)
    order = s.expansion_order(goal, heuristic)
    w = occ.shape[1]
    assert len(order) == full.expansions == int(s.closed_mask().sum())
    assert order[0] == start[0] * w + start[1]
    assert order[-1] == goal[0] * w + goal[1]
    # f of each cell in the order, from the g values of the full search
    g = s._g.reshape(occ.shape[0] + 2, w + 2)[1:-1, 1:-1].ravel()[order]
    dy, dx = np.abs(order // w - goal[0]), np.abs(order % w - goal[1])
    h = (np.where(dx > dy, dx + (math.sqrt(2) - 1) * dy, dy + (math.sqrt(2) - 1) * dx)
         if heuristic == "octile" else np.hypot(dx, dy))
    f = g + h
    assert (np.diff(f) >= -1e-8).all()
    for k in ks:
        if k >= len(order):
            continue
        probe = AStarSearcher(occ, corner_cutting=cutting)
        r = probe.search(start, goal, heuristic, max_expansions=k)
        assert r.expansions == k
        got = set(np.flatnonzero(probe.closed_mask()).tolist())
        want = set(order[:k].tolist())
        differ = got ^ want
        # only cells tied (in f) with the boundary may be swapped
        fk = f[k - 1]
        pos = {int(c): i for i, c in enumerate(order)}
        assert all(abs(f[pos[c]] - fk) < 1e-8 for c in differ), (k, len(differ))


@pytest.mark.parametrize("heuristic", ["euclidean", "octile"])
@pytest.mark.parametrize("cutting", [False, True])
def test_the_order_is_the_order_of_expansion(heuristic, cutting):
    g = random_map((48, 40), obstacles=500, seed=3, keep_free=[(0.5, 0.5), (46.5, 38.5)],
                   connect=[((0.5, 0.5), (46.5, 38.5))])
    check_prefixes(g.occupied, (0, 0), (38, 46), heuristic, cutting,
                   ks=range(1, 2000, 7))


def test_the_order_on_a_city_map():
    occ = load_map(BOSTON).occupied
    free = np.argwhere(~occ)
    start, goal = tuple(map(int, free[0])), tuple(map(int, free[len(free) // 2]))
    check_prefixes(occ, start, goal, "euclidean", False, ks=[1, 2, 10, 100, 1000, 5000, 20000])


def test_the_closed_layer_carries_the_order():
    grid = paper_map(5)
    pb = Problem.create(grid, (1, 1), (11, 11), 0.2)
    mask, order = closed_order(pb)
    assert (closed_set(pb) == mask).all()
    assert sorted(order.tolist()) == np.flatnonzero(mask).tolist()
    d = plan_request(MapStore(), {"map": "paper", "seed": 5, "start": [1, 1], "goal": [11, 11],
                                  "planner": "astar", "robot_radius": 0.2,
                                  "layers": ["closed"]}, Limits())
    ex = d["extras"]["closed"]
    got = np.frombuffer(base64.b64decode(ex["order"]), dtype="<i4")
    assert got.tolist() == order.tolist() and len(got) == ex["count"] == d["expansions"]
    assert ex["bits"] == pack_mask(mask)

