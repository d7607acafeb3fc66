"""Not stopping next to a disc that may walk in (ours, issue 17/18; ``fusion.flee``,
pathfuse.planners.controllers.flee).

The regression replays the dynamic benchmark's tuning family (``pathfuse dynamic --seed 3
--moving 2 --robot model=diff-drive``, scenario 6; not the reported family ``--seed 0``):
the fusion turned away from a random walker 0.8 m ahead, slowed of its own choice and was
walked into, standing, 5.1 s into the episode.  With ``flee`` the window's command that
keeps the largest predicted gap (within the shield) replaces the slowing one and the robot
reaches the goal.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pathfuse.costmap import make_costmap
from pathfuse.planners.controllers.flee import flee_command, rollout_gap
from pathfuse.planners.controllers.fusion import FusionParams
from pathfuse.sweep import unicycle_pose
from pathfuse.world.episode import simulate
from pathfuse.world.generate import generate_scenarios

LIM = (0.0, 1.0, 2.0, 2.0, 4.0)  # vmin, vmax, amax, wmax, alpha (the benchmark's robot)


def _open(n=40, res=0.5, radius=0.25):
    return make_costmap(np.zeros((n, n), dtype=np.bool_), radius, resolution_m=res)


def _brute(x, y, th, v, w, dt, amax, hold_s, horizon_s, radius, dpos, dvel, drad, spread):
    best = math.inf
    cv, cw = v, w
    for k in range(int(round(horizon_s / dt))):
        if k >= int(round(hold_s / dt)):
            cv, cw = max(cv - amax * dt, 0.0), 0.0
        x, y, th = unicycle_pose(x, y, th, cv, cw, dt)
        t = (k + 1) * dt
        for i in range(drad.shape[0]):
            c = dpos[i] + dvel[i] * t
            best = min(best, math.hypot(x - c[0], y - c[1]) - radius - drad[i] - spread * t)
    return best


@pytest.mark.parametrize("seed", range(5))
def test_rollout_gap_against_a_plain_rollout(seed):
    rng = np.random.default_rng(seed)
    cm = _open()
    dpos = rng.uniform(6.0, 14.0, (3, 2))
    dvel = rng.uniform(-0.8, 0.8, (3, 2))
    drad = rng.uniform(0.2, 0.4, 3)
    v, w, th = float(rng.uniform(0, 1)), float(rng.uniform(-2, 2)), float(rng.uniform(-3, 3))
    got = rollout_gap(cm, 10.0, 10.0, th, v, w, 0.1, 2.0, 1.0, 2.0, 0.25, dpos, dvel, drad,
                      0.3)
    want = _brute(10.0, 10.0, th, v, w, 0.1, 2.0, 1.0, 2.0, 0.25, dpos, dvel, drad, 0.3)
    assert got == pytest.approx(want, abs=1e-9)


def test_rollout_into_a_wall_counts_as_contact():
    occ = np.zeros((40, 40), dtype=np.bool_)
    occ[:, 22:] = True  # a wall from x = 11 m
    cm = make_costmap(occ, 0.25, resolution_m=0.5)
    none = np.zeros((0, 2))
    g = rollout_gap(cm, 10.0, 10.0, 0.0, 1.0, 0.0, 0.1, 2.0, 1.0, 2.0, 0.25, none, none,
                    np.zeros(0), 0.3)
    assert g == -math.inf
    g = rollout_gap(cm, 10.0, 10.0, math.pi, 1.0, 0.0, 0.1, 2.0, 1.0, 2.0, 0.25, none, none,
                    np.zeros(0), 0.3)
    assert g == math.inf


def test_no_disc_near_leaves_the_command():
    cm = _open()
    far = np.array([[16.0, 10.0]])
    out = flee_command(cm, 10.0, 10.0, 0.0, 0.5, 0.0, 0.3, 0.1, 0.1, LIM, far,
                       np.array([[-0.8, 0.0]]), np.array([0.3]), None)
    assert out == (0.3, 0.1, False)
    none = np.zeros((0, 2))
    assert flee_command(cm, 10.0, 10.0, 0.0, 0.5, 0.0, 0.3, 0.1, 0.1, LIM, none, none,
                        np.zeros(0), None) == (0.3, 0.1, False)


def test_a_robot_stopping_in_a_discs_way_moves_on():
    """A disc 0.6 m to the robot's left walks at it (0.7 m/s); the controller asks to stop:
    the replacement keeps going (the best predicted gap) and passes the test given."""
    cm = _open()
    dpos = np.array([[10.0, 10.0 + 0.25 + 0.3 + 0.6]])
    dvel = np.array([[0.0, -0.7]])
    drad = np.array([0.3])
    asked = (0.3, 0.0)
    own = rollout_gap(cm, 10.0, 10.0, 0.0, *asked, 0.1, 2.0, 1.0, 2.0, 0.25, dpos, dvel, drad,
                      0.3)
    v, w, done = flee_command(cm, 10.0, 10.0, 0.0, 0.5, 0.0, *asked, 0.1, LIM, dpos, dvel,
                              drad, None)
    assert done and v > 0.5          # faster out of the lane, not a stop in it
    got = rollout_gap(cm, 10.0, 10.0, 0.0, v, w, 0.1, 2.0, 1.0, 2.0, 0.25, dpos, dvel, drad,
                      0.3)
    assert got >= min(own, 0.5) + 0.05
    # every replacement must pass the caller's test: refusing all leaves the command
    assert flee_command(cm, 10.0, 10.0, 0.0, 0.5, 0.0, *asked, 0.1, LIM, dpos, dvel, drad,
                        lambda a, b: False) == (*asked, False)


def test_flee_is_a_switch_of_the_fusion_off_by_default():
    assert FusionParams().flee is False
    assert FusionParams(flee=True).flee is True


def _least_disc_gap(ep) -> float:
    """Centre distance less both radii over the recorded ticks (independent of the world's
    own collision test)."""
    pos = np.asarray(ep.positions)[:, None, :]
    obs = np.asarray(ep.obstacle_positions)
    d = np.hypot(obs[..., 0] - pos[..., 0], obs[..., 1] - pos[..., 1])
    return float((d - ep.scenario.robot.radius_m - np.asarray(ep.obstacle_radii)[None, :]).min())


def test_a_walker_no_longer_walks_into_the_slowed_fusion():
    """Tuning family 3, scenario 6, 2 discs (the study's run seed 6): hit standing with
    ``flee`` off, the goal with it on; checked from the recorded positions too."""
    sc = generate_scenarios(7, moving=2, speed_range=(0.3, 0.8), seed=3,
                            robot={"model": "diff-drive"}, name="dyn-k2")[6]
    off = simulate(sc, planner={"name": "fusion", "params": {"seed": 6}})
    assert off.status.name == "COLLISION"
    assert off.collision_at_fault is False
    assert _least_disc_gap(off) < 0.0
    on = simulate(sc, planner={"name": "fusion", "params": {"seed": 6, "flee": True}})
    assert on.status.name == "SUCCESS", on.message
    gx, gy = sc.goal
    end = on.positions[-1]
    assert math.hypot(end[0] - gx, end[1] - gy) <= sc.goal_tolerance + 1e-9
    assert _least_disc_gap(on) > 0.0
    assert sum(on.shield_counts.values()) == on.n_ticks  # the shield saw every command
