"""The world's goal test on an arc: the early exit changes no answer."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from pathfuse.geometry import point_segment_distance
from pathfuse.sweep import unicycle_pose
from pathfuse.world.world import World


def _by_chords(goal, tol, dt, p0, th0, v, w) -> bool:
    """Every chord of the arc, each counted within the tolerance less its bound (the test
    as it was before the early exit)."""
    gx, gy = goal
    n = max(1, int(math.ceil(math.sqrt(abs(v * w) * dt ** 2 / 8.0 / 1e-6))))
    h = dt / n
    e = abs(v * w) * h * h / 8.0
    ax, ay = p0
    for i in range(1, n + 1):
        bx, by, _ = unicycle_pose(p0[0], p0[1], th0, v, w, i * h)
        if point_segment_distance(gx, gy, ax, ay, bx, by) + e <= tol:
            return True
        ax, ay = bx, by
    return False


def test_goal_on_an_arc_as_by_every_chord() -> None:
    rng = np.random.default_rng(7)
    hits = near = 0
    for _ in range(3000):
        dt = float(rng.choice([0.05, 0.1, 0.25]))
        tol = float(rng.choice([0.1, 0.3, 1.0]))
        p0 = (float(rng.uniform(-1, 1)), float(rng.uniform(-1, 1)))
        th0 = float(rng.uniform(-math.pi, math.pi))
        v = float(rng.uniform(0.05, 2.0)) * float(rng.choice([1.0, -1.0]))
        w = float(rng.uniform(0.05, 4.0)) * float(rng.choice([1.0, -1.0]))
        x1, y1, _ = unicycle_pose(p0[0], p0[1], th0, v, w, dt)
        # goals around the arc's middle, at distances close to the tolerance
        mx, my, _ = unicycle_pose(p0[0], p0[1], th0, v, w, 0.5 * dt)
        a = float(rng.uniform(0, 2 * math.pi))
        r = tol + float(rng.normal(scale=0.01)) * float(rng.choice([1.0, 0.01, 0.0001]))
        goal = (mx + r * math.cos(a), my + r * math.sin(a))
        fake = SimpleNamespace(goal=goal, scenario=SimpleNamespace(goal_tolerance=tol), dt=dt)
        got = World._passes_goal(fake, np.array(p0), np.array([x1, y1]), th0,
                                 np.array([v, w]), True)
        want = _by_chords(goal, tol, dt, p0, th0, v, w)
        assert got == want
        hits += want
        near += abs(r - tol) < 1e-4
    assert 100 < hits < 2900 and near > 300
