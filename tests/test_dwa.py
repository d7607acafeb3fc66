"""The Dynamic Window Approach: its window, its safety, offline and online."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pathfuse import Status, plan, simulate
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.metrics import collision_free, min_clearance
from pathfuse.planners.controllers.dwa import DWAParams
from pathfuse.planners.registry import get_planner
from pathfuse.planners.run import start_online
from pathfuse.problem import Problem
from pathfuse.robot import RobotModel
from pathfuse.sweep import unicycle_pose
from pathfuse.world import World

HALL = {"map": {"rows": ["..............."] * 5}, "start": [1.5, 2.5], "goal": [13.5, 2.5],
        "time_limit": 40}


def _drive(sc, robot, seed=0):
    """Run dwa tick by tick, returning the world's info of every tick and the commands."""
    w = World(dict(sc, robot=robot))
    obs = w.reset(seed)
    spec = get_planner("dwa")
    model = w.robot
    pb = Problem.create(w.scenario.grid, w.scenario.start, w.scenario.goal, model.radius_m,
                        robot=model)
    ctrl = start_online(spec, pb, DWAParams(), w.dt, model.max_speed_mps)
    infos, cmds, prev = [], [], obs.command
    while True:
        a = ctrl.command(obs)
        obs, term, trunc, info = w.step(a)
        infos.append(info)
        cmds.append((np.asarray(a, dtype=float), prev))
        prev = obs.command
        if term or trunc:
            return infos, cmds, model, w


@pytest.mark.parametrize("robot", [
    {"model": "diff-drive", "radius": 0.2},
    {"model": "diff-drive", "radius": 0.3, "max_accel": 0.5, "max_yaw_accel": 1.0,
     "max_yaw_rate": 1.0, "max_speed": 1.5, "min_speed": -0.2},
    {"radius": 0.2, "max_accel": 1.0},
])
def test_dwa_never_commands_beyond_its_window(robot):
    sc = dict(HALL, obstacles=[{"position": [9.5, 2.4], "velocity": [-0.5, 0.0],
                                "radius": 0.3}])
    infos, cmds, m, w = _drive(sc, robot)
    dt = w.dt
    for info, (a, prev) in zip(infos, cmds, strict=True):
        assert not info["clipped"], (a, prev)
        if m.is_diff_drive:
            assert m.min_speed_mps - 1e-12 <= a[0] <= m.max_speed_mps + 1e-12
            assert abs(a[1]) <= m.max_yaw_rate_radps + 1e-12
            assert abs(a[0] - prev[0]) <= m.max_accel_mps2 * dt + 1e-9
            assert abs(a[1] - prev[1]) <= m.max_yaw_accel_radps2 * dt + 1e-9
        else:
            assert math.hypot(*a) <= m.max_speed_mps + 1e-9
            assert math.hypot(*(a - prev)) <= m.max_accel_mps2 * dt + 1e-9
    if robot.get("max_accel", 2.0) >= 1.0:
        # a sluggish robot (0.5 m/s^2, 1 rad/s^2) may not get out of the way in time
        assert infos[-1]["event"] == "reached"


def _dense_static_gap(grid, positions, headings, commands, dt, n=50):
    """Independent re-check: the robot's centre sampled densely along every tick's exact arc,
    its least distance to the occupied squares (pathfuse.metrics, exact point distances)."""
    pts = [positions[0]]
    for k in range(len(commands)):
        for t in np.linspace(dt / n, dt, n):
            x, y, _ = unicycle_pose(*positions[k], headings[k], *commands[k], t)
            pts.append((x, y))
    pts = np.array(pts)
    return min(min_clearance(grid, p[None, :]) for p in pts)


@pytest.mark.parametrize("seed", range(6))
def test_dwa_episodes_rechecked_independently(seed):
    sc = "examples/scenarios/crossing.yaml"
    ep = simulate(sc, planner="dwa", seed=seed, robot={"model": "diff-drive", "radius": 0.2})
    assert ep.status in (Status.SUCCESS, Status.COLLISION, Status.TIMEOUT,
                         Status.LOCAL_MINIMUM)
    if ep.collision_with != "static":
        gap = _dense_static_gap(ep.grid, ep.positions, ep.headings, ep.commands, ep.scenario.dt)
        assert gap >= ep.robot_radius, gap
        # the world's exact minimum agrees with the dense samples (to the sampling)
        assert ep.min_static_clearance_m <= gap - ep.robot_radius + 1e-9


def test_dwa_offline_on_paper_maps_with_a_disc_robot():
    ok = 0
    for seed in range(20):
        g = paper_map(seed)
        r = plan(g, PAPER_START, PAPER_GOAL, planner="dwa", robot_radius_m=0.3)
        assert collision_free(g, r.path, robot_radius_m=0.3), seed
        assert r.info["min_clearance_m"] >= 0
        ok += r.success
        h = r.info["headings"]
        c = r.info["commands"]
        # the path follows the commands of the default diff-drive robot exactly
        for k in range(min(len(c), 30)):
            x, y, th = unicycle_pose(*r.path[k], h[k], *c[k], r.info["dt_s"])
            assert (x, y) == pytest.approx(tuple(r.path[k + 1]), abs=1e-9)
            assert th == pytest.approx(h[k + 1])
    assert ok == 20


def test_dwa_offline_robot_models():
    g = paper_map(4)
    holo = plan(g, PAPER_START, PAPER_GOAL, planner="dwa",
                robot=RobotModel(radius_m=0.2, max_accel_mps2=2.0))
    dd = plan(g, PAPER_START, PAPER_GOAL, planner="dwa", robot_radius_m=0.2)
    assert holo.success and dd.success
    assert holo.info["robot_model"] == "holonomic" and dd.info["robot_model"] == "diff-drive"
    assert not np.array_equal(holo.path, dd.path)


def test_dwa_dodges_a_head_on_disc_where_astar_walks_into_it():
    sc = dict(HALL, obstacles=[{"position": [10.5, 2.5], "velocity": [-0.5, 0.0],
                                "radius": 0.3}])
    robot = {"model": "diff-drive", "radius": 0.2}
    assert simulate(sc, planner="astar", robot=robot).status is Status.COLLISION
    ep = simulate(sc, planner="dwa", robot=robot)
    assert ep.status is Status.SUCCESS, ep.message
    # planning for the shield's passive safety, it steps aside early and wide (it passed
    # within 1 mm before, and under the shield was stopped in the disc's way and hit)
    assert ep.min_obstacle_distance_m > 0.1
    assert ep.shield_counts["asked"] == ep.n_ticks


def test_steadiness_starts_again_for_a_disc_out_of_sight():
    """dwell_steady: a disc's velocity history is dropped on a tick it is not sensed, so a
    disc seen again is not steady before it has been watched for a second again."""
    sc = World(dict(HALL, robot={"model": "diff-drive"})).scenario
    model = World(dict(HALL, robot={"model": "diff-drive"})).robot
    pb = Problem.create(sc.grid, sc.start, sc.goal, model.radius_m, robot=model)
    ctrl = start_online(get_planner("dwa"), pb, DWAParams(dwell_steady=True), 0.1,
                        model.max_speed_mps)
    one = (np.array([[8.0, 2.5]]), np.array([[-0.5, 0.0]]), np.array([0.3]), np.array([7]))
    none = (np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0), np.zeros(0, dtype=np.int64))
    for _ in range(12):
        ctrl._choose(1.5, 2.5, 0.0, 0.0, 0.0, *one)
    assert len(ctrl.steady.hist[7]) > ctrl.steady.n  # watched long enough: steady
    ctrl._choose(1.5, 2.5, 0.0, 0.0, 0.0, *none)
    assert 7 not in ctrl.steady.hist
