"""Forces on a grid (numba): the repulsion of occupied cells and of moving discs.

Obstacle *points* for the forces of eq. 6 are the centres of the occupied
cells of the :class:`~pathfuse.costmap.Costmap` ``cm`` (its occupancy, origin
and resolution; see :mod:`pathfuse.geometry`).

* :func:`grid_repulsion` - eq. 6 summed over the occupied cell centres
  within ``radius_m`` (usually ``rho0_m``; the fusion's ``r2``).  It reads
  only the ``(2 radius / res + 1)^2`` cells around the robot, so its cost does
  not depend on the size of the map.
* :func:`apf_force` - goal attraction (eq. 5) plus :func:`grid_repulsion`.
* :func:`fusion_force` - Algorithm 2: the goal and the path points ahead
  within ``r1`` attract (eq. 9), obstacles within ``r2`` repel.
* :func:`grid_improved_repulsion` - the repulsion of Ge and Cui (2000) used
  by reference method [6]: eq. 6 scaled by ``(rho_g / L)^n`` plus a pull
  towards the target, zero at the target.
* :func:`disc_repulsion` - the repulsion of sensed moving discs (eq. 6 on
  the gap, or the velocity-aware form of Ge and Cui 2002), with the
  tangential ``swerve`` of pathfuse.
* :func:`boundary_repulsion` - ours, the resolution-independent option
  (``static_repulsion="boundary"``): eq. 6 once, on the exact distance ``d``
  from the robot's centre to the nearest point of an occupied square, plus
  ``offset`` (:data:`BOUNDARY_OFFSET_M`, half the paper's 1 m cell), along
  the direction away from that point.  The same obstacle gives the same
  force however finely it is rasterised; at the paper's 1 m cells an
  isolated obstacle cell pushes exactly as in the paper along its faces'
  normals (its centre lies half a cell behind the face).  The per-cell sum
  (``"cells"``) stays the default: it is the paper's model and its numbers.

Examples
--------
>>> import numpy as np
>>> from pathfuse.costmap import make_costmap
>>> occ = np.zeros((5, 5), dtype=bool); occ[2, 3] = True   # one obstacle, centre (3.5, 2.5)
>>> cm = make_costmap(occ, 0.0, lattice=False)
>>> fx, fy = grid_repulsion(2.5, 2.5, cm, 5.0, 2.0, 2.0)
>>> round(fx, 6), round(fy, 6)   # 5 * (1/1 - 1/2) / 1 = 2.5 pointing to -x
(-2.5, 0.0)
"""

from __future__ import annotations

import math

from numba import njit

from pathfuse.field.forces import D_MIN_M, att_force_xy, rep_force_xy, rep_potential_d

__all__ = [
    "BOUNDARY_OFFSET_M",
    "nearest_obstacle_point",
    "boundary_repulsion",
    "boundary_potential",
    "static_repulsion",
    "AHEAD_PROGRESS",
    "AHEAD_PAPER_X",
    "GAP_MIN_M",
    "SIDE_SPEED",
    "grid_repulsion",
    "apf_force",
    "fusion_force",
    "grid_rep_potential",
    "grid_improved_repulsion",
    "disc_repulsion",
]

# "ahead" rules of the fusion planner
AHEAD_PROGRESS = 0
AHEAD_PAPER_X = 1

BOUNDARY_OFFSET_M = 0.5
"""Default offset of the boundary repulsion: half the paper's 1 m cell (metres)."""

GAP_MIN_M = 1e-3
"""Gaps below this (metres) are clamped in the moving-disc repulsion."""
SIDE_SPEED = 0.05
"""Sideways disc speed (m/s) above which the swerve passes behind the disc."""


# inlined: a call per step that takes the Costmap cost the apf loop ~9 % of its steps/s
# on a 256 x 256 map (benchmarks/bench_stepping.py; docs/speed-log.md), and compiles no slower
@njit(cache=True, inline="always")
def grid_repulsion(x, y, cm, k_rep, rho0_m, radius_m):
    """Sum of eq. 6 over occupied cell centres closer than ``radius_m`` to ``(x, y)``.

    Reads only the window of cells whose centres can be within ``radius_m``.
    """
    occ = cm.occ
    ox = cm.ox_m
    oy = cm.oy_m
    res = cm.res_m
    h, w = occ.shape
    rad = radius_m if radius_m < rho0_m else rho0_m
    if rad <= 0.0:
        return 0.0, 0.0
    c0 = int(math.ceil((x - rad - ox) / res - 0.5))
    c1 = int(math.floor((x + rad - ox) / res - 0.5))
    r0 = int(math.ceil((y - rad - oy) / res - 0.5))
    r1 = int(math.floor((y + rad - oy) / res - 0.5))
    c0 = max(c0, 0)
    r0 = max(r0, 0)
    c1 = min(c1, w - 1)
    r1 = min(r1, h - 1)
    fx = 0.0
    fy = 0.0
    rad2 = rad * rad
    inv_rho0 = 1.0 / rho0_m
    x0 = x - (ox + 0.5 * res)
    for r in range(r0, r1 + 1):
        dy = y - (oy + (r + 0.5) * res)
        dy2 = dy * dy
        for c in range(c0, c1 + 1):
            if occ[r, c]:
                dx = x0 - c * res
                d2 = dx * dx + dy2
                if d2 < rad2 and d2 > 0.0:
                    # eq. 6, as rep_force_xy, without the cost of hypot
                    d = math.sqrt(d2)
                    if d > D_MIN_M:
                        inv = 1.0 / d
                        m = k_rep * (inv - inv_rho0) * inv * inv * inv
                        fx += m * dx
                        fy += m * dy
                    else:
                        mag = k_rep * (1.0 / D_MIN_M - inv_rho0) / (D_MIN_M * D_MIN_M)
                        fx += mag * (dx / d)
                        fy += mag * (dy / d)
    return fx, fy


@njit(cache=True)
def nearest_obstacle_point(x, y, cm, cap):
    """The nearest point of an occupied square to ``(x, y)`` within ``cap`` metres (exact).

    Returns ``(d, px, py)``; ``d = cap`` and the point ``(x, y)`` when none is
    closer.  Squares are visited ring by ring outwards from the robot's cell,
    and the search stops once a ring lies beyond the best distance or ``cap``.
    """
    occ = cm.occ
    ox = cm.ox_m
    oy = cm.oy_m
    res = cm.res_m
    h, w = occ.shape
    c0 = int(math.floor((x - ox) / res))
    r0 = int(math.floor((y - oy) / res))
    best = cap
    bx = x
    by = y
    k = 0
    kmax = int(math.ceil(cap / res)) + 1
    while k <= kmax:
        if k >= 1 and (k - 1) * res >= best:
            break
        for rr in range(r0 - k, r0 + k + 1):
            if rr < 0 or rr >= h:
                continue
            edge = rr == r0 - k or rr == r0 + k
            step = 1 if (edge or k == 0) else 2 * k
            cc = c0 - k
            while cc <= c0 + k:
                if 0 <= cc < w and occ[rr, cc]:
                    x0 = ox + cc * res
                    y0 = oy + rr * res
                    px = min(max(x, x0), x0 + res)
                    py = min(max(y, y0), y0 + res)
                    d = math.sqrt((x - px) * (x - px) + (y - py) * (y - py))
                    if d < best:
                        best = d
                        bx = px
                        by = py
                cc += step
        k += 1
    return best, bx, by


@njit(cache=True)
def boundary_repulsion(x, y, cm, k_rep, rho0_m, radius_m, offset_m):
    """Eq. 6 on ``d + offset_m``, ``d`` the exact distance to the nearest occupied square,
    within ``min(radius_m, rho0_m)``; away from the nearest point (ours, see the module
    docstring).  Inside a square (``d = 0``) it pushes away from the square's centre."""
    lim = radius_m if radius_m < rho0_m else rho0_m
    if lim <= offset_m:
        return 0.0, 0.0
    d, px, py = nearest_obstacle_point(x, y, cm, lim - offset_m)
    deff = d + offset_m
    if deff >= lim:
        return 0.0, 0.0
    if d > 0.0:
        ux = (x - px) / d
        uy = (y - py) / d
    else:
        ox = cm.ox_m
        oy = cm.oy_m
        res = cm.res_m
        cx = ox + (math.floor((x - ox) / res) + 0.5) * res
        cy = oy + (math.floor((y - oy) / res) + 0.5) * res
        n = math.hypot(x - cx, y - cy)
        if n == 0.0:
            return 0.0, 0.0
        ux = (x - cx) / n
        uy = (y - cy) / n
    dc = deff if deff > D_MIN_M else D_MIN_M
    m = k_rep * (1.0 / dc - 1.0 / rho0_m) / (dc * dc)
    return m * ux, m * uy


@njit(cache=True)
def boundary_potential(x, y, cm, k_rep, rho0_m, offset_m):
    """Eq. 4 on ``d + offset_m`` (the potential of :func:`boundary_repulsion`)."""
    if rho0_m <= offset_m:
        return 0.0
    d, _, _ = nearest_obstacle_point(x, y, cm, rho0_m - offset_m)
    return rep_potential_d(d + offset_m, k_rep, rho0_m) if d + offset_m < rho0_m else 0.0


@njit(cache=True, inline="always")
def static_repulsion(x, y, cm, k_rep, rho0_m, radius_m, boundary, offset_m):
    """The static map's repulsion: the paper's per-cell sum, or the boundary form."""
    if boundary:
        return boundary_repulsion(x, y, cm, k_rep, rho0_m, radius_m, offset_m)
    return grid_repulsion(x, y, cm, k_rep, rho0_m, radius_m)


@njit(cache=True)
def apf_force(x, y, gx, gy, k_att, k_rep, rho0_m, radius_m, cm, boundary=False,
              offset_m=BOUNDARY_OFFSET_M):
    """Resultant force of the plain APF at ``(x, y)``: eq. 5 to the goal plus eq. 6."""
    fx, fy = att_force_xy(x, y, gx, gy, k_att)
    rx, ry = static_repulsion(x, y, cm, k_rep, rho0_m, radius_m, boundary, offset_m)
    return fx + rx, fy + ry


@njit(cache=True)
def fusion_force(x, y, gx, gy, pts, cum, k, ahead, k_att, k_rep, rho0_m, r1_m, r2_m,
                 cm, boundary=False, offset_m=BOUNDARY_OFFSET_M):
    """Resultant force of Algorithm 2 at ``(x, y)``.

    Attraction (eq. 5) of the goal plus of every path point ``pts[j]``
    strictly inside the circle of radius ``r1_m`` that is *ahead* (eq. 9):

    * ``ahead == AHEAD_PROGRESS``: ``j > k`` (``k`` from
      :func:`pathfuse.field.pathing.advance_progress`) and ``pts[j]`` within
      its reach window; the same for any direction of travel.
    * ``ahead == AHEAD_PAPER_X``: the paper's eq. 8, ``x_p - x > 0``, over all
      path points.

    Repulsion: eq. 6 from every obstacle point closer than ``r2_m`` (and
    ``rho0_m``).  Returns ``(fx, fy, n_attractors)``.
    """
    fx, fy = att_force_xy(x, y, gx, gy, k_att)
    m = pts.shape[0]
    r1sq = r1_m * r1_m
    na = 0
    if ahead == AHEAD_PAPER_X:
        for j in range(m):
            px = pts[j, 0]
            py = pts[j, 1]
            if px - x > 0.0:
                dx = x - px
                dy = y - py
                if dx * dx + dy * dy < r1sq:
                    fx -= k_att * dx
                    fy -= k_att * dy
                    na += 1
    else:
        ex = x - pts[k, 0]
        ey = y - pts[k, 1]
        reach = math.sqrt(ex * ex + ey * ey) + r1_m
        j = k + 1
        while j < m and cum[j] - cum[k] <= reach:
            dx = x - pts[j, 0]
            dy = y - pts[j, 1]
            if dx * dx + dy * dy < r1sq:
                fx -= k_att * dx
                fy -= k_att * dy
                na += 1
            j += 1
    rx, ry = static_repulsion(x, y, cm, k_rep, rho0_m, r2_m, boundary, offset_m)
    return fx + rx, fy + ry, na


@njit(cache=True)
def grid_rep_potential(x, y, cm, k_rep, rho0_m):
    """Sum of eq. 4 over the occupied cell centres closer than ``rho0_m`` to ``(x, y)``.

    The same window as :func:`grid_repulsion`.
    """
    occ = cm.occ
    ox = cm.ox_m
    oy = cm.oy_m
    res = cm.res_m
    h, w = occ.shape
    c0 = max(int(math.ceil((x - rho0_m - ox) / res - 0.5)), 0)
    c1 = min(int(math.floor((x + rho0_m - ox) / res - 0.5)), w - 1)
    r0 = max(int(math.ceil((y - rho0_m - oy) / res - 0.5)), 0)
    r1 = min(int(math.floor((y + rho0_m - oy) / res - 0.5)), h - 1)
    u = 0.0
    rad2 = rho0_m * rho0_m
    for r in range(r0, r1 + 1):
        dy = y - (oy + (r + 0.5) * res)
        for c in range(c0, c1 + 1):
            if occ[r, c]:
                dx = x - (ox + (c + 0.5) * res)
                d2 = dx * dx + dy * dy
                if d2 < rad2:
                    u += rep_potential_d(math.sqrt(d2), k_rep, rho0_m)
    return u


@njit(cache=True)
def grid_improved_repulsion(x, y, tx, ty, cm, k_rep, rho0_m, n, scale_m, boundary=False,
                            offset_m=BOUNDARY_OFFSET_M):
    """The Ge-Cui repulsion at ``(x, y)`` for the target ``(tx, ty)`` on a grid.

    ``(rho_g/L)^n`` times :func:`grid_repulsion` plus ``n U (rho_g/L)^(n-1) /
    L`` towards the target (``U`` = :func:`grid_rep_potential`).  Zero at the
    target.
    """
    dgx = tx - x
    dgy = ty - y
    rg = math.hypot(dgx, dgy)
    if rg == 0.0:
        return 0.0, 0.0
    q = rg / scale_m
    s = q**n
    fx, fy = static_repulsion(x, y, cm, k_rep, rho0_m, rho0_m, boundary, offset_m)
    fx *= s
    fy *= s
    if boundary:
        u = boundary_potential(x, y, cm, k_rep, rho0_m, offset_m)
    else:
        u = grid_rep_potential(x, y, cm, k_rep, rho0_m)
    if u > 0.0:
        m = u * n * q ** (n - 1.0) / scale_m / rg
        fx += m * dgx
        fy += m * dgy
    return fx, fy


@njit(cache=True)
def disc_repulsion(x, y, vx, vy, radius, pos, vel, radii, k_rep, rho0_m, reach_m,
                   velocity_aware, a_max, swerve, ux_des, uy_des):
    """Summed repulsion of sensed discs on a robot disc at ``(x, y)`` moving at ``(vx, vy)``.

    ``pos``, ``vel`` (M, 2) and ``radii`` (M,) describe the discs; only
    discs whose gap (centre distance minus both radii, clamped below at
    :data:`GAP_MIN_M`) is below ``min(reach_m, rho0_m)`` count.
    ``(ux_des, uy_des)`` is the unit direction the robot means to go.

    * position form (``velocity_aware`` false): eq. 6 on the gap, away from
      the disc;
    * velocity form: with ``v_ro`` the closing speed and ``rho_m = v_ro^2 /
      (2 a_max)`` the braking distance, a disc the robot is not approaching,
      or whose gap minus ``rho_m`` exceeds ``rho0_m``, repels nothing;
      otherwise ``k (1 + v_ro / a_max) / (gap - rho_m)^2`` away from the
      disc plus ``k v_ro v_perp / (gap a_max (gap - rho_m)^2)`` along the
      perpendicular part of the relative velocity (Ge and Cui 2002, our
      reading);
    * ``swerve`` (pathfuse's addition, 0 turns it off): a tangential push of
      ``swerve`` times the radial one, scaled by how far ahead the disc is,
      to the side away from the disc (behind a disc that moves across the
      intended motion; to the right for a disc dead ahead).
    """
    fx = 0.0
    fy = 0.0
    lim = min(reach_m, rho0_m)
    for i in range(pos.shape[0]):
        cx = x - pos[i, 0]
        cy = y - pos[i, 1]
        dc = math.sqrt(cx * cx + cy * cy)
        gap = dc - radii[i] - radius
        if dc > 0.0:
            ux = cx / dc
            uy = cy / dc
        else:  # centres coincide: push to the right of the intended motion
            ux = uy_des
            uy = -ux_des
        g = max(gap, GAP_MIN_M)
        if not velocity_aware:
            if gap > lim:
                continue
            rx, ry = rep_force_xy(ux * g, uy * g, k_rep, rho0_m)
        else:
            if gap > reach_m:
                continue
            rvx = vx - vel[i, 0]
            rvy = vy - vel[i, 1]
            v_ro = -(rvx * ux + rvy * uy)  # closing speed towards the disc
            if v_ro <= 0.0:
                continue
            rho_m = v_ro * v_ro / (2.0 * a_max)
            eff = gap - rho_m
            if eff >= rho0_m:
                continue
            e = max(eff, GAP_MIN_M)
            m1 = k_rep * (1.0 + v_ro / a_max) / (e * e)
            # relative velocity minus its component along n_RO = -u
            pvx = rvx - (-v_ro) * ux
            pvy = rvy - (-v_ro) * uy
            pv = math.sqrt(pvx * pvx + pvy * pvy)
            rx = m1 * ux
            ry = m1 * uy
            if pv > 0.0:
                m2 = k_rep * v_ro * pv / (g * a_max * e * e)
                rx += m2 * pvx / pv
                ry += m2 * pvy / pv
        if swerve > 0.0:
            ahead = -(ux * ux_des + uy * uy_des)
            if ahead > 0.0:
                mag = math.sqrt(rx * rx + ry * ry)
                # the side to pass on: behind a disc that moves across the intended
                # motion; else away from the disc's side; a disc dead ahead: to the right
                w = vel[i, 0] * (-uy_des) + vel[i, 1] * ux_des  # disc velocity to the left
                cross = ux_des * (-cy) - uy_des * (-cx)  # > 0: disc left of the motion
                go_left = w < -SIDE_SPEED if abs(w) > SIDE_SPEED else cross < 0.0
                tx = -uy
                ty = ux
                left = tx * (-uy_des) + ty * ux_des  # component along the left normal
                if (left > 0.0) != go_left:
                    tx = -tx
                    ty = -ty
                rx += swerve * mag * ahead * tx
                ry += swerve * mag * ahead * ty
        fx += rx
        fy += ry
    return fx, fy
