"""The Costmap: its constructor's checks and its checks against a brute-force geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pathfuse.costmap import (
    NO_DISCS,
    arc_clear,
    arc_distance,
    costmap_for,
    field_distance,
    make_costmap,
    make_discs,
    move_clear,
    point_clear,
    point_distance,
    segment_clear,
    segment_distance,
)
from pathfuse.geometry import MARGIN_FRAC
from pathfuse.grid import GridMap
from pathfuse.result import ConfigError, PathfuseError
from pathfuse.sweep import unicycle_pose


def _squares(cm):
    """The occupied squares' ``(x0, y0, x1, y1)`` of a costmap."""
    rows, cols = np.nonzero(cm.occ)
    x0 = cm.ox_m + cols * cm.res_m
    y0 = cm.oy_m + rows * cm.res_m
    return x0, y0, x0 + cm.res_m, y0 + cm.res_m


def _brute_squares(cm, px, py):
    """Distance from each point to the nearest occupied square (``inf`` on a free map)."""
    x0, y0, x1, y1 = _squares(cm)
    if x0.size == 0:
        return np.full(np.shape(px), np.inf)
    px = np.asarray(px, dtype=float)[..., None]
    py = np.asarray(py, dtype=float)[..., None]
    dx = np.maximum(np.maximum(x0 - px, px - x1), 0.0)
    dy = np.maximum(np.maximum(y0 - py, py - y1), 0.0)
    return np.hypot(dx, dy).min(axis=-1)


def _brute(cm, px, py):
    """Distance to the squares or the map's outside (0 outside), as the checks define it."""
    px = np.asarray(px, dtype=float)
    py = np.asarray(py, dtype=float)
    edge = np.minimum.reduce([px - cm.ox_m, cm.xmax_m - px, py - cm.oy_m, cm.ymax_m - py])
    return np.maximum(np.minimum(_brute_squares(cm, px, py), edge), 0.0)


def _random_costmap(rng, radius=0.2):
    h, w = rng.integers(4, 14, size=2)
    occ = rng.random((h, w)) < rng.uniform(0.05, 0.35)
    res = float(rng.choice([0.05, 0.1, 0.25, 1.0]))
    origin = (float(rng.uniform(-3, 3)), float(rng.uniform(-3, 3)))
    return make_costmap(occ, radius, origin=origin, resolution_m=res,
                        field_cell_m=res / float(rng.choice([1, 2, 4])))


def _inside(rng, cm, n):
    return (rng.uniform(cm.ox_m, cm.xmax_m, n), rng.uniform(cm.oy_m, cm.ymax_m, n))


def test_the_constructor_fills_every_field():
    occ = np.zeros((3, 4), dtype=np.bool_)
    occ[1, 2] = True
    cm = make_costmap(occ, 0.3, origin=(1.0, -2.0), resolution_m=0.5)
    assert cm.occ.shape == (3, 4) and not cm.occ.flags.writeable
    assert occ.flags.writeable  # the caller's array is left as it was
    assert (cm.ox_m, cm.oy_m, cm.res_m, cm.xmax_m, cm.ymax_m) == (1.0, -2.0, 0.5, 3.0, -0.5)
    assert cm.radius_m == 0.3 and cm.clear_m == 0.3 + MARGIN_FRAC * 0.5
    assert make_costmap(occ, 0.3, clear_m=0.25).clear_m == 0.25
    g = GridMap(occ, resolution=0.5, origin=(1.0, -2.0))
    cg = make_costmap(g, 0.3)
    assert cg.occ is g.occupied and cg[1:8] == cm[1:8]
    assert np.array_equal(cg.field, cm.field)
    assert costmap_for(g, 0.3) is costmap_for(g, 0.3)
    assert costmap_for(g, 0.3) is not costmap_for(g, 0.4)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"occupied": np.zeros((2, 2))}, "occupied: must be a 2-D bool array or a GridMap, got "
                                     "float64 array of shape (2, 2)"),
    ({"occupied": np.zeros(3, dtype=np.bool_)}, "occupied: must be a 2-D bool array"),
    ({"occupied": np.zeros((0, 3), dtype=np.bool_)}, "occupied: must be a 2-D bool array"),
    ({"occupied": [[True]]}, "occupied: must be a 2-D bool array or a GridMap, got [[True]]"),
    ({"radius_m": -0.1}, "radius_m: must be a number >= 0, got -0.1"),
    ({"radius_m": math.nan}, "radius_m: must be a finite number >= 0, got nan"),
    ({"resolution_m": 0.0}, "resolution_m: must be a number > 0, got 0.0"),
    ({"resolution_m": "x"}, "resolution_m: must be a number > 0, got 'x'"),
    ({"origin": (0.0, math.inf)}, "origin[1]: must be a finite number, got inf"),
    ({"origin": 3.0}, "origin: must be two numbers [x, y], got 3.0"),
    ({"clear_m": -1.0}, "clear_m: must be a number >= 0, got -1.0"),
    ({"field_cell_m": 0.0}, "field_cell_m: must be a number > 0, got 0.0"),
])
def test_the_constructor_rejects_bad_input_naming_the_key_and_value(kwargs, message):
    args = {"occupied": np.zeros((2, 2), dtype=np.bool_), "radius_m": 0.2, **kwargs}
    occ = args.pop("occupied")
    radius = args.pop("radius_m")
    with pytest.raises(ConfigError) as e:
        make_costmap(occ, radius, **args)
    assert isinstance(e.value, PathfuseError)
    assert str(e.value).startswith(message)


def test_a_gridmap_brings_its_own_frame():
    g = GridMap.from_rows([".."])
    with pytest.raises(ConfigError, match="origin, resolution_m: must be left out"):
        make_costmap(g, 0.2, resolution_m=0.5)


def test_discs_are_checked():
    d = make_discs([[0.0, 1.0], [2.0, 3.0]], [[0.0, 1.0], [0.0, 0.0]], [0.1, 0.2],
                   [2.0, 0.5])
    assert d.speed_bound_mps.tolist() == [2.0, 0.5]
    assert make_discs([], [], []).pos_m.shape == (0, 2)
    assert NO_DISCS.vel_mps.shape == (0, 2)
    with pytest.raises(ConfigError, match="vel_mps: must be finite numbers of shape"):
        make_discs([[0.0, 1.0]], [[0.0, 1.0, 2.0]], [0.1])
    with pytest.raises(ConfigError, match="speed_bound_mps: must be at least the sensed"):
        make_discs([[0.0, 1.0]], [[0.0, 1.0]], [0.1], [0.5])
    with pytest.raises(ConfigError, match="pos_m: must be finite numbers"):
        make_discs([[0.0, math.nan]], [[0.0, 1.0]], [0.1])


def test_point_distance_and_clear_agree_with_brute_force():
    rng = np.random.default_rng(1)
    for _ in range(40):
        cm = _random_costmap(rng)
        xs, ys = _inside(rng, cm, 60)
        # a few just outside the map too
        xs = np.append(xs, [cm.ox_m - 0.01, cm.xmax_m + 0.3])
        ys = np.append(ys, [cm.oy_m + 0.5 * (cm.ymax_m - cm.oy_m)] * 2)
        want = _brute(cm, xs, ys)
        for x, y, d in zip(xs, ys, want, strict=True):
            got = point_distance(cm, float(x), float(y), 1e9)
            assert got == pytest.approx(d, abs=1e-12)
            cap = 0.5 * cm.res_m
            assert point_distance(cm, float(x), float(y), cap) == pytest.approx(min(d, cap),
                                                                                abs=1e-12)
            if abs(d - cm.clear_m) > 1e-9:
                assert point_clear(cm, float(x), float(y), cm.clear_m) == (d >= cm.clear_m)


def test_segment_distance_and_clear_agree_with_brute_force():
    rng = np.random.default_rng(2)
    for _ in range(30):
        cm = _random_costmap(rng)
        ax, ay = _inside(rng, cm, 25)
        bx, by = ax + rng.normal(0, 2 * cm.res_m, 25), ay + rng.normal(0, 2 * cm.res_m, 25)
        for a0, a1, b0, b1 in zip(ax, ay, bx, by, strict=True):
            n = 4001
            t = np.linspace(0.0, 1.0, n)
            d = _brute(cm, a0 + t * (b0 - a0), a1 + t * (b1 - a1))
            step = math.hypot(b0 - a0, b1 - a1) / (n - 1)
            got = segment_distance(cm, float(a0), float(a1), float(b0), float(b1), 1e9)
            # exact: no sample is closer, and the closest sample is within half a step
            assert got <= d.min() + 1e-12
            assert got >= d.min() - 0.5 * step - 1e-12
            clear = cm.clear_m
            if abs(d.min() - clear) > step:
                assert segment_clear(cm, float(a0), float(a1), float(b0), float(b1),
                                     clear) == (d.min() >= clear)


def test_arc_distance_and_clear_agree_with_brute_force():
    rng = np.random.default_rng(3)
    for _ in range(25):
        cm = _random_costmap(rng)
        xs, ys = _inside(rng, cm, 12)
        for x, y in zip(xs, ys, strict=True):
            th = float(rng.uniform(-math.pi, math.pi))
            v = float(rng.uniform(-1.0, 2.0)) * cm.res_m * 4
            w = float(rng.choice([0.0, rng.uniform(-3.0, 3.0)]))
            dt = float(rng.uniform(0.1, 1.0))
            n = 2001
            pts = np.array([unicycle_pose(float(x), float(y), th, v, w, dt * i / (n - 1))[:2]
                            for i in range(n)])
            d = _brute(cm, pts[:, 0], pts[:, 1])
            step = abs(v) * dt / (n - 1)
            clear = cm.clear_m
            got = arc_distance(cm, float(x), float(y), th, v, w, dt, clear, 1e9)
            assert got <= d.min() + 1e-9  # a lower bound: never misses a contact
            if abs(d.min() - clear) > step + 1e-9:
                assert arc_clear(cm, float(x), float(y), th, v, w, dt,
                                 clear) == (d.min() >= clear)


def test_field_distance_is_a_lower_bound_and_the_edge_exact():
    rng = np.random.default_rng(4)
    for _ in range(30):
        cm = _random_costmap(rng)
        xs, ys = _inside(rng, cm, 80)
        want = _brute_squares(cm, xs, ys)
        for x, y, d in zip(xs, ys, want, strict=True):
            sq, edge = field_distance(cm, float(x), float(y))
            assert sq <= d + 1e-12
            # and not far below it: within a lattice cell's diagonal
            if math.isfinite(d):
                assert sq >= d - 2.0 * math.sqrt(2.0) * cm.field_res_m - 1e-12
            assert edge == pytest.approx(min(x - cm.ox_m, cm.xmax_m - x, y - cm.oy_m,
                                             cm.ymax_m - y), abs=1e-12)


def test_move_clear_is_the_planners_move_rule_against_an_exact_oracle():
    # clear of every square by `clear`, and inside the map by the radius (clear less the
    # margin) only: a robot may touch the map's edge, where segment_clear keeps the margin
    shapely = pytest.importorskip("shapely")
    from shapely.geometry import LineString, Point, box

    rng = np.random.default_rng(7)
    for _ in range(30):
        cm = _random_costmap(rng, radius=float(rng.uniform(0.0, 0.6)))
        x0, y0, x1, y1 = _squares(cm)
        boxes = shapely.union_all([box(*b) for b in zip(x0, y0, x1, y1, strict=True)])
        clear = cm.clear_m
        edge = clear - MARGIN_FRAC * cm.res_m
        xs, ys = _inside(rng, cm, 60)
        for i in range(60):
            a = (float(xs[i]), float(ys[i]))
            b = (float(xs[i - 1]), float(ys[i - 1])) if i % 3 else a
            geom = LineString([a, b]) if a != b else Point(a)
            d = geom.distance(boxes) if not boxes.is_empty else math.inf
            inside = all(cm.ox_m + edge <= p[0] <= cm.xmax_m - edge
                         and cm.oy_m + edge <= p[1] <= cm.ymax_m - edge for p in (a, b))
            if abs(d - clear) > 1e-9:
                assert move_clear(cm, *a, *b, clear) == (inside and d > clear)
    # on a free map a robot may stand its radius from the edge (not its clearance)
    cm = make_costmap(np.zeros((4, 4), dtype=np.bool_), 0.3, origin=(1.0, 2.0))
    x = cm.ox_m + (cm.clear_m - MARGIN_FRAC * cm.res_m)
    assert move_clear(cm, x, 3.0, x, 4.0, cm.clear_m)
    assert not segment_clear(cm, x, 3.0, x, 4.0, cm.clear_m)
    assert not move_clear(cm, x - 1e-9, 3.0, x, 4.0, cm.clear_m)


def test_the_world_kernels_the_bench_warms_exist():
    # bench.warmup names the world's numba kernels to tell a cold cache; a kernel that is
    # gone (the discs' old _clear) made cold_kernels_of(world=True) raise AttributeError
    from pathfuse.bench import warmup

    assert all(hasattr(k, "_cache") for k in warmup._world_kernels())
    assert isinstance(warmup.cold_kernels_of([], metrics=False, world=True), list)
