"""The dwa kernel's pruning (:mod:`pathfuse.planners.controllers.dwa_bound`) is exact: the
probe tells admissibility and the end point as the full rollout does, and the pruned choice
is the exhaustive one (command, cost, admissible count and passing sides, bit for bit)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pathfuse.costmap import Discs, costmap_for
from pathfuse.field.pathing import polyline_cumlen
from pathfuse.grid import GridMap
from pathfuse.planners.controllers.dwa import FIELD_CELL_M, DWAParams, _near_for
from pathfuse.planners.controllers.dwa_bound import ADMISSIBLE, _probe
from pathfuse.planners.controllers.dwa_checks import NO_NEAR, path_blocks
from pathfuse.planners.controllers.dwa_kernel import (
    _choose,
    _passive_penalty,
    _rollout,
    pack_dwa,
    route_tangent,
)
from pathfuse.planners.controllers.dwa_route import _local_goal
from pathfuse.shield import holonomic_stop_disc_gap, unicycle_stop_disc_gap


def _map() -> GridMap:
    rng = np.random.default_rng(5)
    occ = rng.random((50, 70)) < 0.03
    occ[10:35, 30] = True
    occ[20, 40:60] = True
    return GridMap(occ, origin=(0.0, 0.0), resolution=0.1)


def _settings(holonomic: bool, margin: float, **over: float):
    p = DWAParams()
    w = dict(w_align=p.path_align_weight, near_s=p.keep_horizon_s, w_keep=p.keep_weight,
             keep_m=p.keep_m, w_social=p.social_weight, personal_m=p.personal_m,
             w_side=p.side_weight, dwell_s=p.dwell_s, w_dwell=p.dwell_weight)
    w.update(over)
    amax = math.inf if holonomic else 2.0
    return pack_dwa(0.1, 0.0, 1.0, amax, 2.0, 4.0, margin, p.horizon_s, p.sim_step_s, 7,
                    5 if holonomic else 9, p.path_weight, p.goal_weight, p.heading_weight,
                    p.speed_weight, p.obstacle_weight, p.moving_weight, p.obstacle_range_m,
                    p.lookahead_m, p.inflation_decay_m, holonomic, True, **w)


def _state(rng, cm):
    """A free start, a path of a few points from it and 0-3 discs around it."""
    occ = cm.occ
    while True:
        x, y = rng.uniform(0.5, 6.5), rng.uniform(0.5, 4.5)
        r, c = int(y / 0.1), int(x / 0.1)
        if not occ[max(r - 3, 0):r + 4, max(c - 3, 0):c + 4].any():
            break
    pts = [(x, y)]
    for _ in range(int(rng.integers(2, 6))):
        pts.append((pts[-1][0] + rng.uniform(-0.5, 1.5), pts[-1][1] + rng.uniform(-1.0, 1.0)))
    pts_a = np.array(pts)
    nd = int(rng.integers(0, 4))
    dpos = np.array([(x, y)]) + rng.uniform(-2.0, 2.0, (nd, 2))
    dvel = rng.uniform(-0.8, 0.8, (nd, 2))
    drad = rng.uniform(0.1, 0.3, nd)
    return x, y, float(rng.uniform(-math.pi, math.pi)), pts_a, polyline_cumlen(pts_a), \
        dpos, dvel, drad


def _samples(f, th, c0, c1):
    """The samples in the kernel's order: (command, rollout heading, speed, yaw rate)."""
    out = []
    if f.holonomic:
        ndir = 3 * f.w_samples
        for i in range(f.v_samples):
            s = f.max_speed_mps * i / (f.v_samples - 1)
            for j in range(ndir if i > 0 else 1):
                a = 2.0 * math.pi * j / ndir
                ux, uy = s * math.cos(a), s * math.sin(a)
                sp = math.hypot(ux, uy)
                out.append((ux, uy, math.atan2(uy, ux) if sp > 0.0 else th, sp, 0.0))
        return out
    dt, nv, nw = f.dt_s, f.v_samples, f.w_samples
    vlo = max(f.min_speed_mps, c0 - f.max_accel_mps2 * dt)
    vhi = min(f.max_speed_mps, c0 + f.max_accel_mps2 * dt)
    wlo = max(-f.max_yaw_rate_radps, c1 - f.max_yaw_accel_radps2 * dt)
    whi = min(f.max_yaw_rate_radps, c1 + f.max_yaw_accel_radps2 * dt)
    for i in range(nv):
        v = vhi if i == nv - 1 else min(max(vlo + (vhi - vlo) * (i / (nv - 1)), vlo), vhi)
        for j in range(nw + 1):
            if j < nw:
                w = whi if j == nw - 1 else min(max(wlo + (whi - wlo) * (j / (nw - 1)), wlo),
                                                whi)
            else:
                w = min(max(0.0, wlo), whi)
            out.append((v, w, th, v, w))
    return out


def _exhaustive(cm, near, f, clear, tick, x, y, th, c0, c1, pts, cum, dpos, dvel, drad,
                dside):
    """Every sample rolled out, in order, the first of least cost kept (the kernel before
    the pruning)."""
    k = 0
    jg = _local_goal(pts, cum, k, f.max_speed_mps * f.horizon_s + f.lookahead_m + 1.0)
    bb = path_blocks(pts, k, jg)
    nd = drad.shape[0]
    out, sides, reach = np.zeros(3), np.zeros((nd, 2)), np.empty(nd)
    chosen = np.zeros((nd, 2))
    chosen[:, 1] = np.inf
    tx, ty = route_tangent(pts, k, th)
    discs = Discs(dpos, dvel, np.hypot(dvel[:, 0], dvel[:, 1]), drad)
    best, b, count = math.inf, (0.0, 0.0), 0
    for s0, s1, sh, sv, sw in _samples(f, th, c0, c1):
        _rollout(cm, near, f, clear, tick[0], x, y, sh, sv, sw, pts, cum, k, jg, bb, dpos,
                 dvel, drad, out, tx, ty, dside, sides, reach, tick[3])
        if out[1] == 1.0 and nd > 0:
            gap = holonomic_stop_disc_gap(x, y, s0, s1, f.dt_s, f.max_accel_mps2, cm.radius_m,
                                          discs) if f.holonomic else unicycle_stop_disc_gap(
                x, y, th, s0, s1, f.dt_s, f.max_accel_mps2, f.max_yaw_accel_radps2,
                cm.radius_m, discs)
            out[0] += _passive_penalty(gap)
        if out[1] == 1.0:
            count += 1
            if out[0] < best:
                best, b = float(out[0]), (s0, s1)
                chosen[:, :] = sides
    return b, count, best, chosen


@pytest.mark.parametrize("holonomic", [True, False])
def test_pruned_choice_is_the_exhaustive_one(holonomic: bool) -> None:
    from pathfuse.planners.controllers.dwa_kernel import DwaTick
    from pathfuse.planners.controllers.social import EVERY_DISC

    g = _map()
    cm = costmap_for(g, 0.2, field_cell_m=FIELD_CELL_M)
    rng = np.random.default_rng(11 if holonomic else 12)
    checked = admissible = 0
    for trial in range(60):
        f = _settings(holonomic, 0.1 if trial % 4 == 0 else 0.0)
        near = _near_for(g, cm, f) if trial % 2 else NO_NEAR
        x, y, th, pts, cum, dpos, dvel, drad = _state(rng, cm)
        c0, c1 = (rng.uniform(0.0, 1.0), rng.uniform(-1.0, 1.0)) if not holonomic else (
            0.0, 0.0)
        dside = rng.choice([-1.0, 0.0, 1.0], drad.shape[0])
        keep = float(rng.choice([math.inf, 0.1, 0.3]))
        clear = cm.clear_m + float(rng.choice([0.0, 0.05]))
        tick = DwaTick(keep, 0.0, 0.0, EVERY_DISC)
        chosen = np.zeros((drad.shape[0], 2))
        a0, a1, count, best = _choose(cm, near, f, clear, tick, x, y, th, c0, c1, pts, cum, 0,
                                      dpos, dvel, drad, dside, chosen)
        (w0, w1), wcount, wbest, wchosen = _exhaustive(
            cm, near, f, clear, (keep, 0.0, 0.0, EVERY_DISC), x, y, th, c0, c1, pts, cum,
            dpos, dvel, drad, dside)
        assert count == wcount
        if wcount:
            assert (a0, a1, best) == (w0, w1, wbest)
            assert np.array_equal(chosen, wchosen)
            admissible += 1
        checked += 1
    assert admissible > 30


@pytest.mark.parametrize("holonomic", [True, False])
def test_probe_is_the_rollouts_admissibility_and_end(holonomic: bool) -> None:
    # with every critic but the end point's off, the rollout's cost is the probe's bound
    # exactly (the same end pose); with them on, never below it
    g = _map()
    cm = costmap_for(g, 0.2, field_cell_m=FIELD_CELL_M)
    rng = np.random.default_rng(21 if holonomic else 22)
    bare = _settings(holonomic, 0.0, w_align=0.0, w_keep=0.0, w_social=0.0, w_side=0.0,
                     w_dwell=0.0)._replace(obstacle_weight=0.0, moving_weight=0.0)
    full = _settings(holonomic, 0.1)
    seen = {0: 0, 1: 0}
    for _ in range(40):
        x, y, th, pts, cum, dpos, dvel, drad = _state(rng, cm)
        jg = _local_goal(pts, cum, 0, 4.0)
        bb = path_blocks(pts, 0, jg)
        nd = drad.shape[0]
        out, sides, reach = np.zeros(3), np.zeros((nd, 2)), np.empty(nd)
        for _, _, sh, sv, sw in _samples(bare, th, 0.5, 0.0)[::3]:
            for f in (bare, full):
                near = _near_for(g, cm, f)
                st, lb = _probe(cm, near, f, cm.clear_m, x, y, sh, sv, sw, pts, cum, 0, jg, bb,
                                dpos, dvel, drad, reach)
                _rollout(cm, near, f, cm.clear_m, 0.2, x, y, sh, sv, sw, pts, cum, 0, jg, bb,
                         dpos, dvel, drad, out, 1.0, 0.0, np.zeros(nd), sides, reach,
                         np.zeros(0, dtype=np.bool_))
                assert (st == ADMISSIBLE) == (out[1] == 1.0)
                seen[int(st)] += 1
                if st == ADMISSIBLE:
                    if f is bare:
                        assert lb == out[0]
                    else:
                        assert lb <= out[0]
    assert seen[0] > 50 and seen[1] > 200
