"""The dwa kernel's shortcuts return exactly what they replace (bit for bit)."""

from __future__ import annotations

import numpy as np

from pathfuse.costmap import costmap_for, field_distance, segment_distance
from pathfuse.geometry import point_box_distance, segment_box_distance
from pathfuse.grid import GridMap
from pathfuse.planners.controllers.dwa_checks import (
    NO_NEAR,
    NearSquares,
    _field_bound,
    _path_distance,
    _segment_distance,
    _straight_pose,
    _sweep_gap,
    near_squares,
    path_blocks,
)
from pathfuse.sweep import disc_sweep_gaps, edge_distance, segment_static_distance, unicycle_pose


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
            assert _segment_distance(cm, ax, ay, bx, by, cap, slack, NO_NEAR) == want
            hits += want == cap
    assert hits > 1000  # the shortcut's case (nothing within the cap) was exercised


def test_segment_distance_under_a_smaller_cap_is_the_same_value() -> None:
    # the rollouts search only as far as could still change their result (dwa_kernel
    # _rollout): under a smaller cap the distance is the same bit for bit, or the cap
    g = _map()
    rng = np.random.default_rng(2)
    below = 0
    for radius in (0.1, 0.333):
        cm = costmap_for(g, radius)
        for _ in range(3000):
            ax = rng.uniform(cm.ox_m, cm.xmax_m)
            ay = rng.uniform(cm.oy_m, cm.ymax_m)
            a = rng.uniform(0.0, 2.0 * np.pi)
            length = float(rng.choice([0.0, 0.05, 0.2]))
            bx, by = ax + length * np.cos(a), ay + length * np.sin(a)
            slack = float(rng.choice([0.0, 1e-7]))
            wide = float(rng.uniform(0.3, 1.0))
            narrow = float(rng.uniform(0.0, wide))
            r1 = _segment_distance(cm, ax, ay, bx, by, wide, slack, NO_NEAR)
            r2 = _segment_distance(cm, ax, ay, bx, by, narrow, slack, NO_NEAR)
            assert r2 == (r1 if r1 < narrow else narrow)
            below += r1 < narrow
    assert below > 500


def _brute(cm, ax, ay, bx, by, cap, slack):
    """min(cap, the map's edge, every occupied square's exact distance): the search's value."""
    h, w = cm.occ.shape
    best = edge_distance(cm.ox_m, cm.oy_m, cm.xmax_m, cm.ymax_m, ax, ay, bx, by, cap, slack)
    if best == 0.0:
        return 0.0
    res = cm.res_m
    for rr, cc in np.argwhere(cm.occ):
        x0 = cm.ox_m + cc * res
        y0 = cm.oy_m + rr * res
        best = min(best, segment_box_distance(ax, ay, bx, by, x0, y0, x0 + res, y0 + res))
    return best


def _near_cases(cm, rng, n):
    """Segments up to 0.1 m long around the occupied squares, many with an end on a square's
    edge or corner (where ties between squares are)."""
    occ = np.argwhere(cm.occ)
    res = cm.res_m
    for _ in range(n):
        rr, cc = occ[rng.integers(len(occ))]
        ax = cm.ox_m + (cc + rng.choice([rng.uniform(-3, 4), 0.0, 1.0])) * res
        ay = cm.oy_m + (rr + rng.choice([rng.uniform(-3, 4), 0.0, 1.0])) * res
        length = float(rng.choice([0.0, 0.01, 0.05, 0.1]))
        a = rng.choice([rng.uniform(0.0, 2.0 * np.pi), 0.0, 0.5 * np.pi, 0.25 * np.pi])
        yield ax, ay, ax + length * np.cos(a), ay + length * np.sin(a)


def _near_mismatches(cm, near, seed, n):
    rng = np.random.default_rng(seed)
    used = bad = 0
    for ax, ay, bx, by in _near_cases(cm, rng, n):
        cap = float(rng.choice([0.05, 0.3, 0.6, 1.2]))
        slack = float(rng.choice([0.0, 1e-7]))
        got = _segment_distance(cm, ax, ay, bx, by, cap, slack, near)
        want = segment_distance(cm, ax, ay, bx, by, cap, slack)
        assert want == _brute(cm, ax, ay, bx, by, cap, slack)
        bad += got != want
        used += want < cap
    return bad, used


def test_near_squares_give_the_searched_distance() -> None:
    # dwa's near-square lists (dwa_checks.near_squares) stand for the search of the squares:
    # the same value bit for bit, on a map of 0.1 m cells and on 1 m cells split 20 x 20
    # (as dwa's costmap, field_cell_m 0.05), against the search and a brute force
    g = _map()
    rng = np.random.default_rng(7)
    occ = rng.random((12, 15)) < 0.15
    g1 = GridMap(occ, origin=(0.5, -2.0), resolution=1.0)
    for grid, cell in ((g, None), (g, 0.05), (g1, 0.05)):
        for radius in (0.1, 0.333):
            cm = costmap_for(grid, radius, field_cell_m=cell)
            near = near_squares(cm, cm.field_res_m * np.sqrt(0.5) + 0.06, 2.0)
            assert near.sq.shape[0] > 0
            bad, used = _near_mismatches(cm, near, 11, 1500)
            assert bad == 0
            assert used > 300  # squares within the cap: the lists decided


def test_near_squares_test_fails_when_the_lists_are_short() -> None:
    # the test above can fail: lists that keep only each cell's farthest square (the lists
    # are nearest first), searched to their end or stopped early
    g = GridMap(np.random.default_rng(7).random((12, 15)) < 0.15, origin=(0.5, -2.0),
                resolution=1.0)
    cm = costmap_for(g, 0.1, field_cell_m=0.05)
    near = near_squares(cm, cm.field_res_m * np.sqrt(0.5) + 0.06, 2.0)
    start = near.start.copy()
    start[0::2] = np.maximum(start[0::2], start[1::2] - 1)
    for dc in (near.dc, np.zeros(0)):
        bad, _ = _near_mismatches(cm, NearSquares(start, near.sq, near.reach_m, dc), 11, 1500)
        assert bad > 20


def test_near_squares_lists_are_nearest_first() -> None:
    # the early stop of _segment_distance rests on each cell's list being sorted by its
    # distance from the cell's centre (dc), which is that distance
    g = GridMap(np.random.default_rng(3).random((10, 12)) < 0.2, resolution=0.5)
    cm = costmap_for(g, 0.2, field_cell_m=0.05)
    near = near_squares(cm, cm.field_res_m * np.sqrt(0.5) + 0.06, 1.5)
    hs, ws = cm.field.shape
    w = cm.occ.shape[1]
    res = cm.res_m
    lists = 0
    for i in range(hs * ws):
        s0, s1 = near.start[2 * i], near.start[2 * i + 1]
        if s0 < 0 or s1 - s0 < 2:
            continue
        lists += 1
        q, c = divmod(i, ws)
        cx = cm.ox_m + (c + 0.5) * cm.field_res_m
        cy = cm.oy_m + (q + 0.5) * cm.field_res_m
        assert np.all(np.diff(near.dc[s0:s1]) >= 0.0)
        for j in range(s0, s1):
            rr, cc = divmod(int(near.sq[j]), w)
            x0, y0 = cm.ox_m + cc * res, cm.oy_m + rr * res
            assert near.dc[j] == point_box_distance(cx, cy, x0, y0, x0 + res, y0 + res)
    assert lists > 100


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


def _scan(pts: np.ndarray, cum: np.ndarray, k: int, jg: int, x: float,
          y: float) -> tuple[float, float]:
    """Every segment ``k .. jg - 1`` in order, the first of least distance (the brute force
    the blocks stand for)."""
    m = pts.shape[0]
    pd, s_at = np.inf, cum[m - 1]
    for j in range(k, min(jg, m - 1)):
        a, d = pts[j], pts[j + 1] - pts[j]
        l2 = d[0] * d[0] + d[1] * d[1]
        tt = min(max(((x - a[0]) * d[0] + (y - a[1]) * d[1]) / l2, 0.0), 1.0) if l2 > 0 else 0.0
        dd = np.hypot(x - (a[0] + tt * d[0]), y - (a[1] + tt * d[1]))
        if dd < pd:
            pd, s_at = dd, cum[j] + tt * (cum[j + 1] - cum[j])
    return float(pd), float(s_at)


def test_path_distance_blocks_are_a_scan_of_every_segment() -> None:
    # grid paths (axis and diagonal runs, repeated points, a path back over itself: ties)
    # and random polylines; points on the path, beside it and far away
    rng = np.random.default_rng(5)
    for trial in range(300):
        n = int(rng.integers(1, 120))
        if trial % 3 == 0:
            steps = rng.choice([-1, 0, 1], size=(n, 2)) * 0.05
            pts = np.cumsum(np.vstack([[0.0, 0.0], steps]), axis=0)
        elif trial % 3 == 1:
            pts = np.cumsum(np.vstack([[0.0, 0.0], rng.normal(size=(n, 2))]), axis=0)
        else:
            half = np.linspace(0.0, 2.0, n // 2 + 2)
            pts = np.column_stack([np.r_[half, half[::-1]], np.zeros(2 * half.size)])
        cum = np.r_[0.0, np.cumsum(np.hypot(*np.diff(pts, axis=0).T))]
        m = pts.shape[0]
        k = int(rng.integers(0, m))
        jg = int(rng.integers(k, m + 3))
        bb = path_blocks(pts, k, jg)
        for _ in range(20):
            j = int(rng.integers(0, m))
            x, y = pts[j] + rng.normal(scale=float(rng.choice([0.0, 0.03, 0.5, 5.0])), size=2)
            assert _path_distance(pts, cum, k, jg, bb, x, y) == _scan(pts, cum, k, jg, x, y)


def test_straight_pose_is_unicycle_pose() -> None:
    # w == 0 (+0 or -0): the angle's cosine and sine taken once at any h > 0 serve every t
    rng = np.random.default_rng(6)
    for _ in range(5000):
        x, y = rng.normal(scale=float(rng.choice([0.0, 1.0, 50.0])), size=2)
        th = float(rng.choice([0.0, -0.0, np.pi, -np.pi, rng.uniform(-4.0, 4.0)]))
        v = float(rng.choice([0.0, rng.uniform(0.0, 2.0), -rng.uniform(0.0, 2.0)]))
        w = float(rng.choice([0.0, -0.0]))
        h = float(rng.choice([0.1, 0.05, rng.uniform(1e-3, 1.0)]))
        mid = th + 0.5 * (w * h)
        cmid, smid = np.cos(mid), np.sin(mid)
        for t in (h, 2.0 * h, float(rng.uniform(1e-6, 3.0)), 0.0):
            want = unicycle_pose(x, y, th, v, w, t)
            got = _straight_pose(x, y, th, v, w, t, cmid, smid)
            assert [np.float64(a).tobytes() for a in got] == \
                [np.float64(a).tobytes() for a in want]


def test_field_bound_is_field_distance_to_rounding() -> None:
    # sqrt for hypot: a few units in the last place, far within the 1e-9 m that
    # _segment_distance's test keeps to spare (its exactness: the test above)
    g = _map()
    rng = np.random.default_rng(7)
    for radius in (0.1, 0.333):
        cm = costmap_for(g, radius)
        for _ in range(5000):
            x = rng.uniform(cm.ox_m - 1.0, cm.xmax_m + 1.0)
            y = rng.uniform(cm.oy_m - 1.0, cm.ymax_m + 1.0)
            want = field_distance(cm, x, y)[0]
            assert abs(_field_bound(cm, x, y) - want) <= 1e-13 * (1.0 + abs(want))


def _ring_search(occ: np.ndarray, ox: float, oy: float, res: float, ax: float, ay: float,
                 bx: float, by: float, cap: float, slack: float) -> float:
    """segment_static_distance as it was before its bounding-box test (the ring search,
    which computes the exact distance of every occupied square it visits)."""
    h, w = occ.shape
    best = cap
    for px, py in ((ax, ay), (bx, by)):
        de = min(px - ox, ox + w * res - px, py - oy, oy + h * res - py)
        if de < 0.0 or (de == 0.0 and slack == 0.0):
            return 0.0
        best = min(best, de + slack)
    c0 = min(max(int(np.floor((min(ax, bx) - ox) / res)), 0), w - 1)
    c1 = min(max(int(np.floor((max(ax, bx) - ox) / res)), 0), w - 1)
    r0 = min(max(int(np.floor((min(ay, by) - oy) / res)), 0), h - 1)
    r1 = min(max(int(np.floor((max(ay, by) - oy) / res)), 0), h - 1)
    k = 0
    while True:
        if k >= 1 and (k - 1) * res >= best:
            break
        if r0 - k < 0 and c0 - k < 0 and r1 + k >= h and c1 + k >= w:
            break
        for rr in range(max(r0 - k, 0), min(r1 + k, h - 1) + 1):
            for cc in range(max(c0 - k, 0), min(c1 + k, w - 1) + 1):
                ring = k == 0 or rr in (r0 - k, r1 + k) or cc in (c0 - k, c1 + k)
                if ring and occ[rr, cc]:
                    x0, y0 = ox + cc * res, oy + rr * res
                    best = min(best, segment_box_distance(ax, ay, bx, by, x0, y0, x0 + res,
                                                          y0 + res))
        k += 1
    return best


def test_segment_static_distance_is_every_square() -> None:
    # the squares skipped by their gap to the segment's bounding box change nothing: the
    # same value as the exact distance of every square the ring search visits (segments
    # along, across, touching and inside the squares, short and long, caps small and large)
    g = _map()
    occ, (ox, oy), res = g.occupied, g.origin, g.resolution
    rng = np.random.default_rng(8)
    near = 0
    for _ in range(1500):
        ax = float(rng.uniform(ox, ox + occ.shape[1] * res))
        ay = float(rng.uniform(oy, oy + occ.shape[0] * res))
        if rng.random() < 0.3:  # on a square's edge or corner
            ax, ay = ox + round((ax - ox) / res) * res, oy + round((ay - oy) / res) * res
        length = float(rng.choice([0.0, 0.05, 0.1, 0.3, 1.5]))
        a = float(rng.choice([0.0, np.pi / 2, np.pi / 4, rng.uniform(0.0, 2.0 * np.pi)]))
        bx, by = ax + length * np.cos(a), ay + length * np.sin(a)
        cap = float(rng.choice([0.05, 0.2, 0.6, 2.0, np.inf]))
        slack = float(rng.choice([0.0, 1e-7]))
        want = _ring_search(occ, ox, oy, res, ax, ay, bx, by, cap, slack)
        got = segment_static_distance(occ, ox, oy, res, ax, ay, bx, by, cap, slack)
        assert got == want, (ax, ay, bx, by, cap, slack)
        near += 0.0 < want < cap
    assert near > 300
