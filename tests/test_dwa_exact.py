"""The dwa kernel's shortcuts return exactly what they replace (bit for bit)."""

from __future__ import annotations

import numpy as np

from pathfuse.costmap import costmap_for, segment_distance
from pathfuse.grid import GridMap
from pathfuse.planners.controllers.dwa_checks import _segment_distance, _sweep_gap
from pathfuse.sweep import disc_sweep_gaps


def _map() -> GridMap:
    rng = np.random.default_rng(3)
    occ = rng.random((40, 60)) < 0.04
    occ[10:30, 20] = True
    return GridMap(occ, origin=(-1.0, 2.0), resolution=0.1)


def test_segment_distance_shortcut_is_exact() -> None:
    g = _map()
    rng = np.random.default_rng(0)
    hits = 0
    for radius in (0.1, 0.333):
        cm = costmap_for(g, radius)
        for _ in range(4000):
            ax = rng.uniform(cm.ox_m - 0.1, cm.xmax_m + 0.1)
            ay = rng.uniform(cm.oy_m - 0.1, cm.ymax_m + 0.1)
            length = float(rng.choice([0.0, 0.02, 0.1, 0.25]))
            a = rng.uniform(0.0, 2.0 * np.pi)
            bx, by = ax + length * np.cos(a), ay + length * np.sin(a)
            cap = float(rng.choice([0.1, 0.3, 0.6, 1.0]))
            slack = float(rng.choice([0.0, 1e-7]))
            want = segment_distance(cm, ax, ay, bx, by, cap, slack)
            assert _segment_distance(cm, ax, ay, bx, by, cap, slack) == want
            hits += want == cap
    assert hits > 1000  # the shortcut's case (nothing within the cap) was exercised


def test_sweep_gap_is_disc_sweep_gaps() -> None:
    rng = np.random.default_rng(1)
    for _ in range(2000):
        p0, p1, q0, q1 = (rng.normal(size=2) for _ in range(4))
        if rng.random() < 0.2:
            p1 = p0 + (q1 - q0)  # no relative motion
        r, rq = rng.uniform(0.0, 0.5, size=2)
        want = disc_sweep_gaps(p0, p1, r, q0[None, :], q1[None, :], np.array([rq]))[0]
        got = _sweep_gap(p0[0], p0[1], p1[0], p1[1], r, q0[0], q0[1], q1[0], q1[1], rq)
        assert got == want
