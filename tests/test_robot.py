"""Robots with kinematics: the diff-drive model, exact arcs, continuous collisions on arcs,
and every online planner driving a diff-drive robot."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pathfuse import ConfigError, simulate
from pathfuse.costmap import make_costmap
from pathfuse.planners.drive import unicycle_command
from pathfuse.planners.registry import get_planner, planner_names
from pathfuse.robot import DIFF_DRIVE_DEFAULTS, RobotModel
from pathfuse.sweep import (
    arc_disc_gaps,
    arc_static_distance,
    segment_static_distance,
    unicycle_pose,
)
from pathfuse.world import World, load_scenario

ONLINE = [n for n in planner_names() if get_planner(n).online]


def closed_form(x, y, th, v, w, t):
    r = v / w
    return (x + r * (math.sin(th + w * t) - math.sin(th)),
            y - r * (math.cos(th + w * t) - math.cos(th)), th + w * t)


def test_unicycle_pose_matches_the_closed_form_arc():
    rng = np.random.default_rng(0)
    for _ in range(500):
        x, y, th = rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-4, 4)
        v, w, t = rng.uniform(-2, 2), rng.uniform(-3, 3), rng.uniform(0, 2)
        if abs(w) < 1e-3:
            continue
        got = unicycle_pose(x, y, th, v, w, t)
        np.testing.assert_allclose(got, closed_form(x, y, th, v, w, t), atol=1e-9)
    # straight and on the spot
    assert unicycle_pose(1.0, 2.0, math.pi / 2, 2.0, 0.0, 0.5) == pytest.approx((1.0, 3.0,
                                                                                   math.pi / 2))
    assert unicycle_pose(1.0, 2.0, 0.3, 0.0, 1.0, 0.5) == (1.0, 2.0, 0.8)
    # tiny yaw rates: continuous with the straight line (no cancellation)
    a = unicycle_pose(0.0, 0.0, 0.0, 1.0, 1e-9, 1.0)
    assert a[0] == pytest.approx(1.0, abs=1e-12) and abs(a[1]) < 1e-8


def _diff_world(**robot):
    return World({"map": {"rows": ["." * 20] * 20}, "start": [10.0, 5.0], "goal": [19.0, 19.0],
                  "robot": {"model": "diff-drive", "radius": 0.2, "heading": 0.0,
                            "max_speed": 2.0, **robot}, "dt": 0.1, "time_limit": 100})


def test_world_drives_the_exact_circle_and_the_heading():
    w = _diff_world(max_accel=100, max_yaw_accel=100)
    obs = w.reset()
    assert obs.heading == 0.0 and obs.command.tolist() == [0.0, 0.0]
    v, om = 1.0, 0.5
    for k in range(1, 40):
        obs, term, trunc, info = w.step((v, om))
        assert not term and not info["clipped"]
        ex, ey, eth = closed_form(10.0, 5.0, 0.0, v, om, 0.1 * k)
        assert obs.position.tolist() == pytest.approx([ex, ey], abs=1e-9)
        assert obs.heading == pytest.approx(eth, abs=1e-12)
        # on the circle of radius v / omega around (10, 7)
        assert math.hypot(obs.position[0] - 10.0, obs.position[1] - 7.0) == pytest.approx(2.0)


def test_world_clips_commands_to_the_limits_and_the_acceleration_window():
    w = _diff_world(max_accel=1.0, max_yaw_rate=1.5, max_yaw_accel=2.0)
    w.reset()
    obs, *_, info = w.step((5.0, -5.0))
    assert info["clipped"] and obs.command.tolist() == pytest.approx([0.1, -0.2])
    prev = obs.command
    for _ in range(30):
        obs, *_ = w.step((5.0, -5.0))
        dv, dw = obs.command - prev
        assert abs(dv) <= 0.1 + 1e-12 and abs(dw) <= 0.2 + 1e-12
        assert 0.0 <= obs.command[0] <= 2.0 and abs(obs.command[1]) <= 1.5
        prev = obs.command
    assert obs.command.tolist() == pytest.approx([2.0, -1.5])
    # no reverse unless min_speed < 0
    obs, *_ = w.step((-3.0, 0.0))
    assert obs.command[0] == pytest.approx(1.9)


def test_holonomic_acceleration_limit():
    w = World({"map": {"rows": ["." * 10] * 3}, "start": [1.5, 1.5], "goal": [9.0, 1.5],
               "robot": {"max_accel": 2.0}, "dt": 0.1})
    w.reset()
    obs, *_ = w.step((1.0, 0.0))
    assert obs.velocity.tolist() == pytest.approx([0.2, 0.0])


def _dense_arc_min(occ, x, y, th, v, w, dt, n=20000):
    best = math.inf
    for t in np.linspace(0.0, dt, n):
        px, py, _ = unicycle_pose(x, y, th, v, w, t)
        best = min(best, segment_static_distance(occ, 0.0, 0.0, 0.5, px, py, px, py, 10.0))
    return best


def test_arc_static_distance_is_a_tight_lower_bound():
    rng = np.random.default_rng(1)
    occ = rng.random((16, 16)) < 0.15
    occ.setflags(write=False)
    checked = 0
    for _ in range(60):
        x, y, th = rng.uniform(1, 7), rng.uniform(1, 7), rng.uniform(-3, 3)
        v, w = rng.uniform(0.2, 2.0), rng.uniform(-3, 3)
        if abs(w) < 0.05:
            continue
        dense = _dense_arc_min(occ, x, y, th, v, w, 0.5)
        # the dense samples are at most (arc length / n) / 2 from the true minimum
        slack = abs(v) * 0.5 / 20000
        thr = dense  # the decision threshold right at the true distance
        lb = arc_static_distance(occ, 0.0, 0.0, 0.5, x, y, th, v, w, 0.5, thr, 10.0)
        assert lb <= dense + 1e-12
        assert lb >= dense - slack - 1e-4   # coarse pieces: within 0.1 mm
        # at a threshold, the decision is exact to the sampling
        for margin in (-1e-3, 1e-3):
            lb = arc_static_distance(occ, 0.0, 0.0, 0.5, x, y, th, v, w, 0.5, dense + margin,
                                     10.0)
            assert (lb < dense + margin) == (margin > slack) or abs(margin) <= slack
        checked += 1
    assert checked > 40


def test_arc_disc_gaps_against_dense_sampling():
    rng = np.random.default_rng(2)
    for _ in range(100):
        x, y, th = rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-3, 3)
        v, w, dt = rng.uniform(0.5, 2.0), rng.uniform(-3, 3), 0.5
        q0 = rng.uniform(-2, 2, (3, 2))
        q1 = q0 + rng.uniform(-1, 1, (3, 2))
        radii = rng.uniform(0.1, 0.5, 3)
        gaps = arc_disc_gaps(x, y, th, v, w, dt, 0.2, q0, q1, radii)
        ts = np.linspace(0.0, dt, 4001)
        p = np.array([unicycle_pose(x, y, th, v, w, t)[:2] for t in ts])
        for j in range(3):
            q = q0[j] + np.outer(ts / dt, q1[j] - q0[j])
            dense = float((np.hypot(*(p - q).T) - 0.2 - radii[j]).min())
            rel = (abs(v) + float(np.hypot(*(q1[j] - q0[j]))) / dt) * dt / 4000
            assert gaps[j] <= dense + 1e-12
            assert gaps[j] >= dense - rel - 1e-4


def test_a_diff_drive_robot_cutting_a_corner_on_an_arc_collides():
    # the chord from start to end is clear of the block, the arc bulges into it
    sc = {"map": {"rows": ["..........", "....#.....", ".........."]},
          "start": [3.0, 0.55], "goal": [9.5, 0.5], "dt": 1.0,
          "robot": {"model": "diff-drive", "radius": 0.05, "heading": 1.0, "max_accel": 100,
                    "max_yaw_rate": 10, "max_yaw_accel": 100, "max_speed": 5}}
    w = World(sc)
    w.reset()
    x1, y1, _ = unicycle_pose(3.0, 0.55, 1.0, 2.0, -2.0, 1.0)
    chord = segment_static_distance(w.costmap.occ, 0.0, 0.0, 1.0, 3.0, 0.55, x1, y1, 5.0)
    assert chord > 0.4   # the chord alone misses by far
    _, term, _, info = w.step((2.0, -2.0))
    assert term and info["collision"] == "static" and info["static_gap"] < 0


def test_robot_model_and_block_round_trip():
    m = RobotModel.diff_drive(radius_m=0.3, max_speed_mps=2.0, clearance_m=0.1)
    assert m.max_accel_mps2 == DIFF_DRIVE_DEFAULTS["max_accel_mps2"]
    assert RobotModel.from_dict(m.to_dict()) == m
    assert RobotModel.from_dict(None) == RobotModel.from_dict({}) == RobotModel()
    sc = load_scenario({"map": {"rows": ["...."]}, "start": [0.5, 0.5], "goal": [3.5, 0.5],
                        "robot": {"model": "diff-drive", "max_yaw_rate": 1.0}})
    assert load_scenario(sc.to_dict()).robot == sc.robot
    with pytest.raises(ConfigError, match="robot.max_accel_mps2: must be a number > 0"):
        RobotModel(max_accel_mps2=0.0)


def test_unicycle_command_stays_in_the_window_and_brakes_for_walls():
    occ = np.zeros((10, 10), dtype=np.bool_)
    occ[:, 6] = True   # a wall at x = 6
    cm = make_costmap(occ, 0.2, clear_m=0.2)
    rng = np.random.default_rng(3)
    for _ in range(300):
        v0, w0 = rng.uniform(0, 1), rng.uniform(-2, 2)
        ux, uy = rng.uniform(-1, 1, 2)
        v, w = unicycle_command(cm, 3.0, 5.0, rng.uniform(-3, 3), v0, w0, ux,
                                uy, 0.1, 0.0, 1.0, 2.0, 2.0, 4.0)
        assert max(0.0, v0 - 0.2) - 1e-12 <= v <= min(1.0, v0 + 0.2) + 1e-12
        assert max(-2.0, w0 - 0.4) - 1e-12 <= w <= min(2.0, w0 + 0.4) + 1e-12
    # heading at the wall with a 0.2 m gap at 0.8 m/s: brakes so that it can stop in time
    v, _ = unicycle_command(cm, 5.6, 5.0, 0.0, 0.8, 0.0, 1.0, 0.0, 0.1, 0.0,
                            1.0, 2.0, 2.0, 4.0)
    assert v < 0.8 and v * 0.1 + v * v / 4.0 <= 0.2
    # with a 0.3 m gap it may still speed up: 0.09 m this tick + 0.2025 m to stop fit
    v, _ = unicycle_command(cm, 5.5, 5.0, 0.0, 0.8, 0.0, 1.0, 0.0, 0.1, 0.0,
                            1.0, 2.0, 2.0, 4.0)
    assert v == pytest.approx(0.9)


@pytest.mark.parametrize("name", ONLINE)
def test_every_online_planner_drives_a_diff_drive_robot(name):
    sc = {"map": {"rows": ["..........", "..........", "....##....", "....##....",
                           "..........", ".........."]},
          "start": [0.5, 0.5], "goal": [9.5, 5.5],
          "robot": {"radius": 0.2, "model": "diff-drive"}}
    ep = simulate(sc, planner=name)
    assert ep.status.name == "SUCCESS", (name, ep.message)
    assert ep.min_static_clearance_m >= 0
    assert ep.headings.shape == (ep.n_ticks + 1,) and ep.commands.shape == (ep.n_ticks, 2)
    rb = ep.robot
    assert rb.is_diff_drive
    v, w = ep.commands.T
    assert np.all(v <= rb.max_speed_mps + 1e-12) and np.all(v >= rb.min_speed_mps - 1e-12)
    assert np.all(np.abs(w) <= rb.max_yaw_rate_radps + 1e-12)
    dv = np.diff(np.concatenate([[0.0], v]))
    dw = np.diff(np.concatenate([[0.0], w]))
    assert np.all(np.abs(dv) <= rb.max_accel_mps2 * 0.1 + 1e-9)
    assert np.all(np.abs(dw) <= rb.max_yaw_accel_radps2 * 0.1 + 1e-9)
    # the recorded poses follow the recorded commands exactly
    for k in range(ep.n_ticks):
        x, y, th = unicycle_pose(*ep.positions[k], ep.headings[k], v[k], w[k], 0.1)
        assert (x, y, th) == pytest.approx((*ep.positions[k + 1], ep.headings[k + 1]),
                                           abs=1e-9)
    traj = ep.trajectory()
    assert traj.shape == (ep.n_ticks + 1, 4)


@pytest.mark.parametrize("name", ONLINE)
def test_diff_drive_trajectories_rechecked_independently(name):
    """Every tick's exact arc sampled densely and measured by pathfuse.metrics (exact point
    distances to the squares): never closer than the world's own minimum, and no contact
    unless the world reported a static collision."""
    from pathfuse.metrics import min_clearance

    ep = simulate("examples/scenarios/crossing.yaml", planner=name,
                  robot={"model": "diff-drive", "radius": 0.2})
    pts = [ep.positions[0]]
    for k in range(ep.n_ticks):
        for t in np.linspace(0.0, ep.scenario.dt, 21)[1:]:
            pts.append(unicycle_pose(*ep.positions[k], ep.headings[k], *ep.commands[k], t)[:2])
    gap = min(min_clearance(ep.grid, np.asarray(p)[None, :]) for p in pts) - 0.2
    assert ep.min_static_clearance_m <= gap + 1e-9
    if ep.collision_with != "static":
        assert gap >= 0.0
