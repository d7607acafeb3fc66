"""The numba kernel of Model Predictive Path Integral control
(see :mod:`pathfuse.planners.controllers.mppi`).

:func:`mppi_optimise` runs one MPPI iteration: it builds the batch of control
sequences (the nominal one, two pure-pursuit guides along the path, a braking
sequence and the nominal plus the given Gaussian noise, each clipped step by
step to the robot's limits and acceleration windows), rolls each out (exact
unicycle arcs or straight moves), scores it with the critics and replaces the
nominal sequence with the softmax-weighted mean of the batch (or with the
fast guide when that scores better, unless switched off).  The static map,
the robot's radius and the clearance lattice come as one
:class:`~pathfuse.costmap.Costmap`, the settings as one :class:`MppiSettings`
(read by name, filled by :func:`pack_mppi`).

The static clearance of a point is read from a lower-bound field (metres from
each cell centre of a fine lattice to the nearest occupied square, less half
a lattice cell's diagonal; the Costmap's ``field``, :func:`pathfuse.costmap.field_distance`):
``field[c] - |p - c|`` is a lower bound of the distance from ``p`` to the
occupied squares (the distance is 1-Lipschitz).  Between two rollout points
``a`` and ``b`` at least ``c`` away from every obstacle, the whole segment is
at least ``sqrt(c^2 - |ab|^2 / 4)`` away; an arc leaves its chord by at most
``|v omega| h^2 / 8``.  Where these bounds say a step comes closer than the
radius, the chord's exact distance (:func:`pathfuse.costmap.segment_distance`)
less that bound decides.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pathfuse.costmap import field_distance, segment_distance
from pathfuse.planners.controllers.social import dwell_shortfall
from pathfuse.sweep import unicycle_pose

__all__ = ["mppi_optimise", "pack_mppi", "path_inflation", "MppiSettings"]

MARGIN_COST = 1.0
"""Inside the robot's safety margin the obstacle cost grows by this much per margin width."""
N_FIXED = 4
"""Samples that are not noise: the nominal sequence, the two guides, the braking sequence."""


class MppiSettings(NamedTuple):
    """The settings of :func:`mppi_optimise`, read by name (one argument), from
    :func:`pack_mppi`.  The map, its frame, the robot's radius and the clearance lattice are
    the :class:`~pathfuse.costmap.Costmap`'s."""

    dt_s: float
    model_dt_s: float
    min_speed_mps: float
    max_speed_mps: float
    max_accel_mps2: float
    max_yaw_rate_radps: float
    max_yaw_accel_radps2: float
    holonomic: bool
    margin_m: float
    temperature: float
    collision_cost: float
    obstacle_weight: float
    inflation_radius_m: float
    cost_scaling_factor: float
    path_align_weight: float
    path_follow_weight: float
    goal_weight: float
    goal_distance_m: float
    path_angle_weight: float
    lookahead_m: float
    disc_collision_cost: float
    disc_proximity_weight: float
    disc_decay_m: float
    smoothness_weight: float
    prefer_forward_weight: float
    std0: float
    """The noise of the first control (m/s)."""
    std1: float
    """The noise of the second control (m/s holonomic, rad/s diff-drive)."""
    seg_max_m: float
    """The longest segment of the path followed (rewritten with the path)."""
    goal_x_m: float
    goal_y_m: float
    obstacle_peak_weight: float
    slow_guide_speed_mps: float
    keep_better_guide: bool
    social_weight: float
    personal_m: float
    dwell_s: float
    dwell_weight: float


def pack_mppi(dt, model_dt, vmin, vmax, amax, wmax, alpha, holonomic, margin, temperature,
              w_coll, w_obs, infl_radius, infl_k, w_align, w_prog, w_goal, goal_dist, w_head,
              lookahead, w_dcoll, w_dprox, disc_decay, w_smooth, w_fwd, std0, std1, seg_max,
              gx, gy, w_peak, slow, keep_guide, w_social=0.0, personal_m=0.5, dwell_s=0.0,
              w_dwell=0.0):
    """The settings of :func:`mppi_optimise`.

    Examples
    --------
    >>> s = pack_mppi(0.1, 0.1, 0.0, 1.0, 2.0, 2.0, 4.0, False, 0.0, 0.3, 1e4, 1.0, 0.55,
    ...               10.0, 1.0, 1.0, 5.0, 1.4, 2.0, 1.0, 1e4, 1.0, 0.3, 0.1, 5.0, 0.2, 0.4,
    ...               0.5, 9.0, 9.0, 1.0, 0.3, True)
    >>> s.max_speed_mps, s.seg_max_m, s.holonomic, s._replace(seg_max_m=2.0).seg_max_m
    (1.0, 0.5, False, 2.0)
    """
    return MppiSettings(
        float(dt), float(model_dt), float(vmin), float(vmax), float(amax), float(wmax),
        float(alpha), bool(holonomic), float(margin), float(temperature), float(w_coll),
        float(w_obs), float(infl_radius), float(infl_k), float(w_align), float(w_prog),
        float(w_goal), float(goal_dist), float(w_head), float(lookahead), float(w_dcoll),
        float(w_dprox), float(disc_decay), float(w_smooth), float(w_fwd), float(std0),
        float(std1), float(seg_max), float(gx), float(gy), float(w_peak), float(slow),
        bool(keep_guide), float(w_social), float(personal_m), float(dwell_s), float(w_dwell))


@njit(cache=True, inline="always")
def _wrap(a):
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@njit(cache=True)
def path_inflation(cm, f, pts, relative):
    """The inflation cost ``exp(-factor x gap)`` at each path point (the baseline the rollouts'
    obstacle critic is measured against); zeros when ``relative`` is false."""
    out = np.zeros(pts.shape[0])
    if not relative:
        return out
    for i in range(pts.shape[0]):
        gap = field_distance(cm, pts[i, 0], pts[i, 1])[0] - cm.radius_m
        if gap < f.inflation_radius_m:
            out[i] = math.exp(-f.cost_scaling_factor * gap)
    return out


@njit(cache=True, inline="always")
def _clip_uni(pv, pw, v, w, h, f):
    a = f.max_accel_mps2 * h
    b = f.max_yaw_accel_radps2 * h
    v = min(max(v, max(f.min_speed_mps, pv - a)), min(f.max_speed_mps, pv + a))
    w = min(max(w, max(-f.max_yaw_rate_radps, pw - b)), min(f.max_yaw_rate_radps, pw + b))
    return v, w


@njit(cache=True, inline="always")
def _clip_holo(px, py, ux, uy, h, f):
    vmax = f.max_speed_mps
    s = math.hypot(ux, uy)
    if s > vmax:
        ux *= vmax / s * (1.0 - 1e-12)
        uy *= vmax / s * (1.0 - 1e-12)
    lim = f.max_accel_mps2 * h
    if math.isfinite(lim):
        dx = ux - px
        dy = uy - py
        n = math.hypot(dx, dy)
        if n > lim:  # onto the window's edge, a hair inside (the world never clips it)
            ux = px + dx * (lim / n) * (1.0 - 1e-12)
            uy = py + dy * (lim / n) * (1.0 - 1e-12)
    return ux, uy


@njit(cache=True, inline="always")
def _turn_to(p0, p1, e, vcap, h, alpha, f):
    """A unicycle's command towards a heading error ``e``: the yaw rate that turns it in one
    step as far as the heading can still stop (angular acceleration ``alpha``), the speed
    ``vcap`` times cos^2 of the error (0 beyond 90 degrees), clipped to the window from
    ``(p0, p1)``."""
    wd = abs(e) / h
    if math.isfinite(alpha):
        wd = min(wd, math.sqrt(2.0 * alpha * abs(e)))
    wd = wd if e >= 0.0 else -wd
    ce = math.cos(e)
    vd = vcap * ce * ce if abs(e) < 0.5 * math.pi else 0.0
    return _clip_uni(p0, p1, vd, wd, h, f)


@njit(cache=True)
def _clip_sequence(seq, f, c0, c1):
    """Clip a sequence in place, step by step, to the limits and the acceleration windows
    (the first step's window is the tick's, the others the model step's)."""
    p0 = c0
    p1 = c1
    holo = f.holonomic
    for t in range(seq.shape[0]):
        h = f.dt_s if t == 0 else f.model_dt_s
        if holo:
            a, b = _clip_holo(p0, p1, seq[t, 0], seq[t, 1], h, f)
        else:
            a, b = _clip_uni(p0, p1, seq[t, 0], seq[t, 1], h, f)
        seq[t, 0] = a
        seq[t, 1] = b
        p0 = a
        p1 = b


@njit(cache=True)
def _track(px, py, pts, cum, j, k0, fwd, back):
    """The nearest path segment to ``(px, py)`` around segment ``j`` (never before ``k0``):
    ``(segment, distance, fraction along it)``."""
    m = pts.shape[0]
    if m == 1:
        return 0, math.hypot(px - pts[0, 0], py - pts[0, 1]), 0.0
    if j > m - 2:  # past the last segment's start: the last segment (segment m - 1 would
        j = m - 2  # read pts[m], past the end, found by running the kernel interpreted)
    lo = j
    while lo > k0 and cum[j] - cum[lo - 1] <= back:
        lo -= 1
    hi = j
    while hi < m - 2 and cum[hi + 1] - cum[j] <= fwd:
        hi += 1
    best = j
    bd = np.inf
    bd2 = np.inf
    bt = 0.0
    for s in range(lo, hi + 1):
        ax = pts[s, 0]
        ay = pts[s, 1]
        vx = pts[s + 1, 0] - ax
        vy = pts[s + 1, 1] - ay
        l2 = vx * vx + vy * vy
        tt = 0.0
        if l2 > 0.0:
            # min(max(dot / l2, 0), 1) without the division where it clamps (exact: l2 > 0,
            # and a correctly rounded quotient of dot >= l2 is >= 1)
            dot = (px - ax) * vx + (py - ay) * vy
            if dot >= l2:
                tt = 1.0
            elif dot > 0.0:
                tt = min(dot / l2, 1.0)
        ex = px - (ax + tt * vx)
        ey = py - (ay + tt * vy)
        # exact too: a squared distance more than 1e-12 relative above the best's square
        # cannot give a hypot below the best (both round within some 1e-16 of the same
        # ex, ey), so its hypot is left out
        if ex * ex + ey * ey > bd2:
            continue
        d = math.hypot(ex, ey)
        if d < bd:
            bd = d
            # (no shortcut below 1e-150 m, where the square would underflow)
            bd2 = d * d * (1.0 + 1e-12) if d > 1e-150 else np.inf
            best = s
            bt = tt
    return best, bd, bt


@njit(cache=True)
def _point_at(pts, cum, s):
    """The path point at arc length ``s`` (clamped to the path)."""
    m = pts.shape[0]
    if s >= cum[m - 1]:
        return pts[m - 1, 0], pts[m - 1, 1]
    if s <= 0.0:
        return pts[0, 0], pts[0, 1]
    lo = 0
    hi = m - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if cum[mid] <= s:
            lo = mid
        else:
            hi = mid
    seg = cum[hi] - cum[lo]
    u = (s - cum[lo]) / seg if seg > 0.0 else 0.0
    return (pts[lo, 0] + u * (pts[hi, 0] - pts[lo, 0]),
            pts[lo, 1] + u * (pts[hi, 1] - pts[lo, 1]))


@njit(cache=True)
def _guide(seq, f, cm, x, y, th, c0, c1, pts, cum, k0, look, vslow):
    """A pure-pursuit sequence (ours): towards a carrot ``look`` of path ahead, turning as
    fast as the heading can still stop, slowing to stop at the goal.  With ``vslow > 0`` its
    speed is regulated by the clearance, as Nav2's regulated pure pursuit does: the limit
    times ``gap / inflation_radius_m``, at least ``vslow``."""
    vmax = f.max_speed_mps
    px = x
    py = y
    pth = th
    p0 = c0
    p1 = c1
    j = k0
    holo = f.holonomic
    amax = f.max_accel_mps2
    alpha = f.max_yaw_accel_radps2
    gx = f.goal_x_m
    gy = f.goal_y_m
    fwd = vmax * max(f.dt_s, f.model_dt_s) + 2.0 * f.seg_max_m
    for t in range(seq.shape[0]):
        h = f.dt_s if t == 0 else f.model_dt_s
        j, _, tt = _track(px, py, pts, cum, j, k0, fwd, 2.0 * f.seg_max_m)
        s = cum[j] + tt * (cum[min(j + 1, cum.shape[0] - 1)] - cum[j])
        cx, cy = _point_at(pts, cum, s + look)
        dg = math.hypot(gx - px, gy - py)
        vcap = vmax
        if math.isfinite(amax):
            # the speed from which braking in steps of a h stops at the goal
            vcap = min(vmax, amax * (math.sqrt(0.25 * h * h + 2.0 * dg / amax) - 0.5 * h))
        if vslow > 0.0:
            gap = field_distance(cm, px, py)[0] - cm.radius_m
            vcap = min(vcap, max(vslow, vmax * gap / f.inflation_radius_m))
        behind = (cx == gx and cy == gy and
                  (gx - px) * math.cos(pth) + (gy - py) * math.sin(pth) <= 0.0)
        if holo:
            dx = cx - px
            dy = cy - py
            n = math.hypot(dx, dy)
            a = 0.0
            b = 0.0
            if n > 1e-12:
                a = dx / n * vcap
                b = dy / n * vcap
            a, b = _clip_holo(p0, p1, a, b, h, f)
            px += a * h
            py += b * h
        elif behind:  # past the goal: brake rather than turn back
            a, b = _clip_uni(p0, p1, 0.0, 0.0, h, f)
            px, py, pth = unicycle_pose(px, py, pth, a, b, h)
        else:
            a, b = _turn_to(p0, p1, _wrap(math.atan2(cy - py, cx - px) - pth), vcap, h,
                            alpha, f)
            px, py, pth = unicycle_pose(px, py, pth, a, b, h)
        seq[t, 0] = a
        seq[t, 1] = b
        p0 = a
        p1 = b


@njit(cache=True)
def _brake(seq, f, c0, c1):
    """Braking as hard as the limits allow, the yaw rate unwinding likewise."""
    p0 = c0
    p1 = c1
    holo = f.holonomic
    for t in range(seq.shape[0]):
        h = f.dt_s if t == 0 else f.model_dt_s
        if holo:
            a, b = _clip_holo(p0, p1, 0.0, 0.0, h, f)
        else:
            a, b = _clip_uni(p0, p1, 0.0, 0.0, h, f)
        seq[t, 0] = a
        seq[t, 1] = b
        p0 = a
        p1 = b


# Long on purpose (~140 lines): every critic scores a sampled sequence in one pass over its
# steps, sharing the step's pose, static gap, path progress and disc gaps; split into one
# function per critic, each would walk the rollout again or pass those locals in and out,
# for every one of batch_size sequences per tick.  The geometry is in helpers
# (field_distance, segment_distance, _track, _point_at, dwell_shortfall).
@njit(cache=True)
def _score(seq, cm, f, thr, x, y, th, c0, c1, pts, cum, pexp, k0, goal_mode, dpos,
           dvel, drad, dsteady):
    """The cost of one control sequence (the critics, summed with their weights)."""
    n = seq.shape[0]
    holo = f.holonomic
    radius = cm.radius_m
    margin = f.margin_m
    infl_r = f.inflation_radius_m
    infl_k = f.cost_scaling_factor
    segmax = f.seg_max_m
    std0 = f.std0
    std1 = f.std1
    gx = f.goal_x_m
    gy = f.goal_y_m
    nd = drad.shape[0]
    px = x
    py = y
    pth = th
    ca, ea = field_distance(cm, x, y)
    j = k0
    cost = 0.0
    obs = 0.0
    align = 0.0
    goal = 0.0
    smooth = 0.0
    back = 0.0
    prox = 0.0
    tc = -1
    depth = 0.0
    p0 = c0
    p1 = c1
    tt = 0.0
    tnow = 0.0
    hit = False
    peak = 0.0
    # ours (pathfuse.planners.controllers.social): the least predicted gap to each disc
    dgap = np.full(nd, np.inf)
    for t in range(n):
        h = f.dt_s if t == 0 else f.model_dt_s
        a = seq[t, 0]
        b = seq[t, 1]
        d0 = (a - p0) / std0
        d1 = (b - p1) / std1
        smooth += d0 * d0 + d1 * d1
        p0 = a
        p1 = b
        if holo:
            nx = px + a * h
            ny = py + b * h
            nth = pth
            dev = 0.0
        else:
            nx, ny, nth = unicycle_pose(px, py, pth, a, b, h)
            dev = abs(a * b) * h * h / 8.0
            if a < 0.0:
                back += -a * h
        cb, eb = field_distance(cm, nx, ny)
        c = min(ca, cb)
        half = 0.5 * math.hypot(nx - px, ny - py)
        seg = math.sqrt(c * c - half * half) if c > half else 0.0
        # the distance to the map's outside is concave along a segment: its least at an end
        if seg - dev < thr or min(ea, eb) - dev < thr:
            # too close by the lower bounds: the chord's exact distance decides
            d = segment_distance(cm, px, py, nx, ny,
                                        thr + dev + 1e-6)
            if d - dev < thr:
                # a collision with the static map: the earlier, the costlier; it ends here
                cost += f.collision_cost * (2.0 * n - t) / n
                hit = True
                break
        j, d, tt = _track(nx, ny, pts, cum, j, k0, 2.0 * half + 2.0 * segmax, 2.0 * segmax)
        gap = cb - radius  # the squares inflate, the map's edge does not (not an obstacle)
        if gap < infl_r:
            # beyond what the global path itself pays here (none where it has room)
            e = math.exp(-infl_k * gap) - max(pexp[j], pexp[min(j + 1, pexp.shape[0] - 1)])
            if e > 0.0:
                obs += e
                if e > peak:
                    peak = e
        if margin > 0.0 and gap < margin:
            obs += MARGIN_COST * (margin - gap) / margin
        for i in range(nd):
            # the disc predicted at constant velocity; the least gap over the step, in
            # closed form between the two linear motions (the arc's chord less its bound)
            qx = dpos[i, 0] + dvel[i, 0] * tnow
            qy = dpos[i, 1] + dvel[i, 1] * tnow
            ex = px - qx
            ey = py - qy
            ddx = (nx - px) - dvel[i, 0] * h
            ddy = (ny - py) - dvel[i, 1] * h
            l2 = ddx * ddx + ddy * ddy
            u = 0.0
            if l2 > 0.0:
                u = min(1.0, max(0.0, -(ex * ddx + ey * ddy) / l2))
            g = math.hypot(ex + u * ddx, ey + u * ddy) - radius - drad[i] - dev
            if g < dgap[i]:
                dgap[i] = g
            if g < 0.0:
                if tc < 0:
                    tc = t
                depth = max(depth, min(-g / (radius + drad[i]), 1.0))
            else:
                prox += math.exp(-g / f.disc_decay_m)
        align += d
        if goal_mode:
            goal += math.hypot(nx - gx, ny - gy)
        px = nx
        py = ny
        pth = nth
        ca = cb
        ea = eb
        tnow += h
    m = pts.shape[0]
    s_end = cum[j] + tt * (cum[min(j + 1, m - 1)] - cum[j])
    cost += f.path_follow_weight * (cum[m - 1] - s_end)
    cost += f.obstacle_weight * obs / n + f.obstacle_peak_weight * peak \
        + f.smoothness_weight * smooth / n + f.prefer_forward_weight * back
    if tc >= 0:
        cost += f.disc_collision_cost * (1.0 + depth + (n - tc) / n)
    cost += f.disc_proximity_weight * prox / n
    if f.social_weight > 0.0:
        # personal space: the worst disc's shortfall, relative, squared
        soc = 0.0
        for i in range(nd):
            if dgap[i] < f.personal_m:
                sh = (f.personal_m - max(dgap[i], 0.0)) / f.personal_m
                soc = max(soc, sh * sh)
        cost += f.social_weight * soc
    if f.dwell_s > 0.0 and f.dwell_weight > 0.0 and not hit:
        # ours (the dwell critic): the robot may have to stand where the rollout ends
        cost += f.dwell_weight * dwell_shortfall(px, py, tnow, dpos, dvel, drad, radius,
                                                 f.dwell_s, f.personal_m, dsteady)
    if goal_mode:
        cost += f.goal_weight * goal / n
    else:
        cost += f.path_align_weight * align / n
        if not holo:
            cx, cy = _point_at(pts, cum, s_end + f.lookahead_m)
            if math.hypot(cx - px, cy - py) > 1e-9:
                cost += f.path_angle_weight * abs(
                    _wrap(math.atan2(cy - py, cx - px) - pth)) / math.pi
    return cost, hit


@njit(cache=True)
def mppi_optimise(cm, f, x, y, th, c0, c1, nominal, noise, ctrl, costs, pts, cum,
                  pexp, k0, goal_mode, dpos, dvel, drad, dsteady):
    """One MPPI update from the pose ``(x, y, th)`` and the last command ``(c0, c1)``.

    ``cm`` is the static map with the robot's radius and the clearance lattice, ``f`` the
    :class:`MppiSettings`.
    ``nominal`` (T, 2) is the previous optimal sequence shifted by the caller;
    on return it holds the new one.  ``noise`` (K, T, 2) holds standard normal
    draws (the first ``N_FIXED`` rows unused), ``ctrl`` (K, T, 2) and ``costs``
    (K,) are work buffers (on return: the clipped samples and their softmax
    weights, unnormalised).  ``k0`` is the robot's progress index on the path
    ``pts`` (cumulative lengths ``cum``); ``goal_mode`` switches the goal critic
    on; ``dpos``, ``dvel``, ``drad`` are the sensed discs.  Returns ``(a0, a1,
    cost, collision_free_samples)``: the first control of the new sequence
    (inside the window the world allows) and the cost of the new sequence.
    """
    nk = ctrl.shape[0]
    n = ctrl.shape[1]
    # the clearance a rollout must keep: the radius, or what a robot already closer has
    radius = cm.radius_m
    here = segment_distance(cm, x, y, x, y, radius)
    thr = min(radius, here * (1.0 - 1e-9))
    std0 = f.std0
    std1 = f.std1
    for t in range(n):
        ctrl[0, t, 0] = nominal[t, 0]
        ctrl[0, t, 1] = nominal[t, 1]
    _clip_sequence(ctrl[0], f, c0, c1)
    _guide(ctrl[1], f, cm, x, y, th, c0, c1, pts, cum, k0, f.lookahead_m, 0.0)
    # a regulated guide that slows near obstacles and keeps close to the path (it threads
    # narrow passages)
    _guide(ctrl[2], f, cm, x, y, th, c0, c1, pts, cum, k0, 0.5 * f.lookahead_m,
           f.slow_guide_speed_mps)
    _brake(ctrl[3], f, c0, c1)
    for k in range(N_FIXED, nk):
        for t in range(n):
            ctrl[k, t, 0] = nominal[t, 0] + std0 * noise[k, t, 0]
            ctrl[k, t, 1] = nominal[t, 1] + std1 * noise[k, t, 1]
        _clip_sequence(ctrl[k], f, c0, c1)
    best = np.inf
    free = 0
    for k in range(nk):
        c, hit = _score(ctrl[k], cm, f, thr, x, y, th, c0, c1, pts, cum, pexp, k0,
                        goal_mode, dpos, dvel, drad, dsteady)
        costs[k] = c
        if c < best:
            best = c
        if not hit:
            free += 1
    guide = costs[1]
    lam = f.temperature
    total = 0.0
    for k in range(nk):
        wk = math.exp(-(costs[k] - best) / lam)
        costs[k] = wk
        total += wk
    for t in range(n):
        s0 = 0.0
        s1 = 0.0
        for k in range(nk):
            s0 += costs[k] * ctrl[k, t, 0]
            s1 += costs[k] * ctrl[k, t, 1]
        nominal[t, 0] = s0 / total
        nominal[t, 1] = s1 / total
    # the mean of clipped sequences keeps their limits; rounding aside, clip once more
    _clip_sequence(nominal, f, c0, c1)
    # the guide instead when it scores better than the mean (ours: on an open path the
    # noise's weighted mean is never exactly straight, the guide is)
    mean, _ = _score(nominal, cm, f, thr, x, y, th, c0, c1, pts, cum, pexp, k0,
                     goal_mode, dpos, dvel, drad, dsteady)
    if f.keep_better_guide and guide <= mean:
        for t in range(n):
            nominal[t, 0] = ctrl[1, t, 0]
            nominal[t, 1] = ctrl[1, t, 1]
        mean = guide
    return nominal[0, 0], nominal[0, 1], mean, free
