"""dwa's lane escape (ours, issue 18; :mod:`pathfuse.planners.controllers.dwa_escape`): the
kernel on hand-made scenes, and each mechanism it fixes on the IR-SIM training world episode
that collided without it (``examples/irsim-train``; not held out)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from pathfuse.costmap import costmap_for
from pathfuse.grid import GridMap
from pathfuse.planners.controllers.dwa import DWAParams
from pathfuse.planners.controllers.dwa_escape import escape_command, standing_contact_s
from pathfuse.planners.controllers.dwa_kernel import pack_dwa
from pathfuse.sweep import unicycle_pose

EVERY = np.zeros(0, dtype=np.bool_)
R = 0.25


def _settings():
    p = DWAParams()
    # the shipped IR-SIM robot: 1 m/s, 2 m/s^2, 2 rad/s, 4 rad/s^2, dt 0.1 s
    return pack_dwa(0.1, 0.0, 1.0, 2.0, 2.0, 4.0, 0.0, p.horizon_s, p.sim_step_s, p.v_samples,
                    p.w_samples, p.path_weight, p.goal_weight, p.heading_weight,
                    p.speed_weight, p.obstacle_weight, p.moving_weight, p.obstacle_range_m,
                    p.lookahead_m, p.inflation_decay_m, False, True,
                    w_social=p.social_weight, personal_m=p.personal_m,
                    w_side=p.side_weight, dwell_s=p.dwell_s, w_dwell=p.dwell_weight)


def _corridor():
    """A 20 m x 4 m corridor (walls along y = 0 and y = 4), cells of 0.1 m."""
    occ = np.zeros((40, 200), dtype=np.bool_)
    occ[0, :] = True
    occ[-1, :] = True
    g = GridMap(occ, 0.1)
    return costmap_for(g, R)


def _path():
    pts = np.array([[1.0, 2.0], [19.0, 2.0]])
    return pts, np.array([0.0, 18.0])


def _gaps(x, y, th, c0, c1, v, w, dpos, dvel, drad, steps):
    """The least gap to the discs (constant velocity) while the robot holds (v, w) from the
    window of (c0, c1) for ``steps`` ticks of 0.1 s (independent of the kernel)."""
    least = math.inf
    for i in range(steps):
        x, y, th = unicycle_pose(x, y, th, v, w, 0.1)
        q = dpos + dvel * (0.1 * (i + 1))
        least = min(least, float((np.hypot(q[:, 0] - x, q[:, 1] - y) - drad - R).min()))
    return least


def test_standing_contact_time_is_exact():
    p = np.array([[3.0, 0.4]])
    v = np.array([[-1.0, 0.0]])
    r = np.array([0.25])
    # the disc comes within 0.5 m of (0, 0) when its x is sqrt(0.5^2 - 0.4^2) = 0.3
    assert standing_contact_s(0.0, 0.0, 0.25, 5.0, p, v, r, EVERY) == pytest.approx(2.7)
    assert standing_contact_s(0.0, 0.0, 0.25, 2.6, p, v, r, EVERY) == math.inf
    assert standing_contact_s(0.0, 0.6, 0.25, 5.0, p, v, r, EVERY) == pytest.approx(
        3.0 - math.sqrt(0.25 - 0.04))
    assert standing_contact_s(0.0, 0.0, 0.25, 5.0, p, v, r, np.array([False])) == math.inf


def test_escape_leaves_the_lane_of_a_faster_walker_from_behind():
    """A robot standing in the middle of the corridor, a walker 2.5 m behind it in its lane
    at 1.4 m/s (faster than the robot): standing (dwa's choice from rest) is walked into at
    about 1.4 s; the escape's first step turns out of the lane, inside the window."""
    cm = _corridor()
    f = _settings()
    pts, cum = _path()
    dpos = np.array([[2.5, 2.0]])
    dvel = np.array([[1.4, 0.0]])
    drad = np.array([0.25])
    x, y, th = 5.5, 2.0, 0.0
    assert standing_contact_s(x, y, R, 3.0, dpos, dvel, drad, EVERY) == pytest.approx(
        (3.0 - 0.5) / 1.4)
    v, w, hd = escape_command(cm, f, 4.0, x, y, th, 0.0, 0.0, 0.0, 0.0, pts, cum, 0, dpos,
                              dvel, drad, EVERY, EVERY, math.nan)
    assert not math.isnan(hd)
    assert 0.0 <= v <= 0.2 + 1e-12 and abs(w) <= 0.4 + 1e-12 and (v, w) != (0.0, 0.0)
    # it turns off the walker's line (to either side)
    assert 0.0 < abs(hd) < math.pi
    # the same robot with its escape switched off by a walker that leaves: nothing changes
    v2, w2, hd2 = escape_command(cm, f, 4.0, x, y, th, 0.0, 0.0, 0.0, 0.0, pts, cum, 0, dpos,
                                 -dvel, drad, EVERY, EVERY, math.nan)
    assert (v2, w2) == (0.0, 0.0) and math.isnan(hd2)
    # nor for a walker that is not trusted (seen to wander)
    v3, w3, hd3 = escape_command(cm, f, 4.0, x, y, th, 0.0, 0.0, 0.1, 0.0, pts, cum, 0, dpos,
                                 dvel, drad, EVERY, np.array([False]), math.nan)
    assert (v3, w3) == (0.1, 0.0) and math.isnan(hd3)


def test_escape_keeps_dwas_choice_when_the_choice_is_not_touched():
    """Standing would be walked into, but dwa's chosen sample already leaves the lane: kept."""
    cm = _corridor()
    f = _settings()
    pts, cum = _path()
    dpos = np.array([[9.0, 2.0]])
    dvel = np.array([[-1.0, 0.0]])
    drad = np.array([0.25])
    x, y, th = 5.0, 2.0, math.pi / 2  # facing the free side, moving already
    assert standing_contact_s(x, y, R, 4.0, dpos, dvel, drad, EVERY) < 4.0
    assert _gaps(x, y, th, 1.0, 0.0, 1.0, 0.0, dpos, dvel, drad, 15) > 0.0
    v, w, hd = escape_command(cm, f, 4.0, x, y, th, 1.0, 0.0, 1.0, 0.0, pts, cum, 0, dpos,
                              dvel, drad, EVERY, EVERY, math.nan)
    assert (v, w) == (1.0, 0.0) and math.isnan(hd)


irsim = pytest.importorskip("irsim", reason="IR-SIM is an optional extra")

from pathfuse.integrations.irsim import example_worlds_dir  # noqa: E402
from pathfuse.integrations.irsim_run import run_irsim_episode  # noqa: E402

TRAIN = Path(example_worlds_dir()).parent / "irsim-train"


def test_dwa_escapes_a_faster_walker_from_behind():
    """lane_escape: dwa commanded v = 0 from the first tick while a walker at 1.4 m/s came
    from behind in its lane (fast_from_behind, seed 1) and was walked into at t = 1.7 s
    (standing scored best: its samples from rest cannot outrun the walker and the moving
    ones pay the walker's reach while they stop).  With the escape it turns out of the
    lane and the walker passes."""
    world = TRAIN / "fast_from_behind.yaml"
    off = run_irsim_episode(world, "dwa", 1, {"lane_escape": False}, time_limit_s=5.0)
    assert off.status.name == "COLLISION" and off.collision_with == "person"
    assert off.collision_at_fault is False  # walked into while standing
    ep = run_irsim_episode(world, "dwa", 1, time_limit_s=5.0)
    assert ep.status.name == "TIMEOUT" and ep.social.min_gap_m > 0.1
    # the walker from behind (the first person) has passed the robot
    assert ep.people_positions[-1, 0, 0] > ep.positions[-1, 0] + 0.5


def test_dwa_leaves_a_head_on_pairs_lane_rather_than_standing_at_the_wall():
    """lane_escape: after the first pair, dwa stood by the upper wall of a 4.5 m corridor
    (y = 5.23, as high as it can be) 0.01 m inside the lane of the second pair's upper walker
    and was walked into after 3 s of standing (west_three_lanes_wide, seed 5).  With the
    escape it crosses below both walkers of that pair before they arrive."""
    world = TRAIN / "west_three_lanes_wide.yaml"
    off = run_irsim_episode(world, "dwa", 5, {"lane_escape": False}, time_limit_s=11.0)
    assert off.status.name == "COLLISION" and off.collision_with == "person"
    assert off.collision_at_fault is False
    ep = run_irsim_episode(world, "dwa", 5, time_limit_s=11.0)
    assert ep.status.name == "TIMEOUT" and ep.social.min_gap_m > 0.3
    # it passed the second pair (walkers 3 and 4, the upper lanes) below both
    k = int(np.argmax(ep.people_positions[:, 2, 0] >= ep.positions[:, 0]))
    assert k > 0 and ep.positions[k, 1] < ep.people_positions[k, 2, 1]
