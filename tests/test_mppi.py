"""Model Predictive Path Integral control: offline and online, both robot models, its
limits, its seed, a BARN world and a head-on disc."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from pathfuse import GridMap, Status, plan, simulate
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.metrics import collision_free, min_clearance, segment_clearances
from pathfuse.planners.controllers.mppi import MPPIParams, clearance_field
from pathfuse.planners.registry import get_planner, planner_names
from pathfuse.planners.run import start_online
from pathfuse.problem import Problem
from pathfuse.robot import RobotModel
from pathfuse.sweep import segment_static_distance, unicycle_pose
from pathfuse.world import World

BARN = Path(__file__).parent / "data" / "barn"
HALL = {"map": {"rows": ["..............."] * 5}, "start": [1.5, 2.5], "goal": [13.5, 2.5],
        "time_limit": 40}
POSTS = {"map": {"rows": ["............", "....#...#...", "............", "......#.....",
                          "............"]},
         "start": [1.5, 2.5], "goal": [10.5, 2.5], "time_limit": 40}
DIFF = {"model": "diff-drive", "radius": 0.25}
HOLO = {"radius": 0.25, "max_accel": 2.0}


def test_registered_after_dwa():
    names = planner_names()
    assert names.index("mppi") == names.index("dwa") + 1
    spec = get_planner("mppi")
    assert spec.online and spec.offline and spec.uses_astar
    assert spec.params_cls is MPPIParams and spec.defaults()["seed"] == 0


def test_clearance_field_is_a_lower_bound():
    rng = np.random.default_rng(3)
    occ = rng.random((12, 16)) < 0.15
    for res, cell in ((0.05, 0.0125), (0.5, 0.5), (1.0, 0.2)):
        g = GridMap(occ, resolution=res, origin=(-0.3, 1.1))
        field, r = clearance_field(g, cell)
        assert field.shape == (12 * round(res / r), 16 * round(res / r))
        assert clearance_field(g, cell)[0] is field  # cached per map
        x0, y0, x1, y1 = g.bounds
        for x, y in zip(rng.uniform(x0, x1, 300), rng.uniform(y0, y1, 300), strict=True):
            c = min(int((x - x0) / r), field.shape[1] - 1)
            q = min(int((y - y0) / r), field.shape[0] - 1)
            lb = field[q, c] - math.hypot(x - (x0 + (c + 0.5) * r), y - (y0 + (q + 0.5) * r))
            exact = segment_static_distance(g.occupied, x0, y0, res, x, y, x, y, 100.0,
                                            100.0)  # squares only: the edge pushed away
            assert lb <= exact + 1e-12
            if exact > 0:
                assert lb >= exact - 2.0 * r  # and tight to about a lattice cell
    # one lattice cell per map cell: the map's distance field less a half-diagonal
    g = GridMap(occ, resolution=0.1)
    field, r = clearance_field(g, 0.5)
    assert r == 0.1 and np.array_equal(field, g.distance_field - 0.1 * math.sqrt(0.5))


@pytest.mark.parametrize("robot", [None, RobotModel(radius_m=0.3, max_accel_mps2=2.0)])
def test_offline_paper_maps_collision_free(robot):
    for seed in range(6):
        g = paper_map(seed)
        r = plan(g, PAPER_START, PAPER_GOAL, planner="mppi", robot_radius_m=0.3, robot=robot)
        assert r.status is Status.SUCCESS, (seed, r.message)
        assert collision_free(g, r.path, robot_radius_m=0.3), seed
        assert r.path[0].tolist() == list(PAPER_START) and r.path[-1].tolist() == \
            list(PAPER_GOAL)
        assert r.info["robot_model"] == ("diff-drive" if robot is None else "holonomic")
        h, c, dt = r.info["headings"], r.info["commands"], r.info["dt_s"]
        for k in range(len(c)):  # the path is what the commands drive, exactly
            if robot is None:
                x, y, th = unicycle_pose(*r.path[k], h[k], *c[k], dt)
            else:
                x, y = r.path[k] + c[k] * dt
            assert (x, y) == pytest.approx(tuple(r.path[k + 1]), abs=1e-9)


def test_offline_without_the_shield_still_keeps_clear():
    g = paper_map(2)
    rb = RobotModel.diff_drive(radius_m=0.3, shield=False)
    r = plan(g, PAPER_START, PAPER_GOAL, planner="mppi", robot_radius_m=0.3, robot=rb)
    assert r.status is Status.SUCCESS, r.message
    assert collision_free(g, r.path, robot_radius_m=0.3)
    assert r.info["shield_counts"].sum() == 0


def test_seeded():
    g = paper_map(5)
    a = plan(g, PAPER_START, PAPER_GOAL, planner="mppi", robot_radius_m=0.2)
    b = plan(g, PAPER_START, PAPER_GOAL, planner="mppi", robot_radius_m=0.2)
    c = plan(g, PAPER_START, PAPER_GOAL, planner="mppi", robot_radius_m=0.2, seed=7)
    assert np.array_equal(a.path, b.path) and np.array_equal(a.info["commands"],
                                                             b.info["commands"])
    assert a.success and c.success
    assert not np.array_equal(a.path, c.path)
    e1 = simulate(POSTS, planner="mppi", robot=DIFF)
    e2 = simulate(POSTS, planner="mppi", robot=DIFF)
    e3 = simulate(POSTS, planner={"name": "mppi", "params": {"seed": 1}}, robot=DIFF)
    assert np.array_equal(e1.positions, e2.positions)
    assert np.array_equal(e1.commands, e2.commands)
    assert not np.array_equal(e1.positions, e3.positions)


@pytest.mark.parametrize("robot", [DIFF, HOLO])
def test_plain_mppi_update(robot):
    # without the guide taking over, the weighted mean alone drives (the plain MPPI update)
    plain = {"name": "mppi", "params": {"keep_better_guide": False}}
    ep = simulate(POSTS, planner=plain, robot=robot)
    assert ep.status is Status.SUCCESS, ep.message
    assert ep.min_static_clearance_m >= 0
    assert not np.array_equal(ep.positions, simulate(POSTS, planner="mppi",
                                                     robot=robot).positions)


def _independent_static_gap(ep, n=20):
    """The robot's centre sampled along every tick (its exact arc, or its straight move), its
    least distance to the occupied squares less the radius (pathfuse.metrics)."""
    pts = [ep.positions[0]]
    for k in range(ep.n_ticks):
        for t in np.linspace(ep.scenario.dt / n, ep.scenario.dt, n):
            if ep.scenario.robot.is_diff_drive:
                x, y, _ = unicycle_pose(*ep.positions[k], ep.headings[k], *ep.commands[k], t)
            else:
                x, y = ep.positions[k] + ep.commands[k] * t
            pts.append((x, y))
    return min_clearance(ep.grid, np.array(pts)) - ep.robot_radius


@pytest.mark.parametrize("robot", [DIFF, HOLO, {"radius": 0.25}])
@pytest.mark.parametrize("sc", [HALL, POSTS])
def test_online_reaches_the_goal(sc, robot):
    ep = simulate(sc, planner="mppi", robot=robot)
    assert ep.status is Status.SUCCESS, ep.message
    assert ep.min_static_clearance_m >= 0
    assert _independent_static_gap(ep) >= -1e-9
    assert ep.shield_counts.get("emergency", 0) == 0


def _drive(sc, robot):
    """Run mppi tick by tick; the world's info of every tick and (command, last command)."""
    w = World(dict(sc, robot=robot))
    obs = w.reset(0)
    m = w.robot
    pb = Problem.create(w.scenario.grid, w.scenario.start, w.scenario.goal, m.radius_m, robot=m)
    ctrl = start_online(get_planner("mppi"), pb, MPPIParams(), w.dt, m.max_speed_mps)
    infos, cmds, prev = [], [], obs.command
    while True:
        a = ctrl.act(obs)  # the controller's own command, before the shield
        obs, term, trunc, info = w.step(a)
        infos.append(info)
        cmds.append((np.asarray(a, dtype=float), prev))
        prev = obs.command
        if term or trunc:
            return infos, cmds, m, w


@pytest.mark.parametrize("robot", [
    {"model": "diff-drive", "radius": 0.2},
    {"model": "diff-drive", "radius": 0.3, "max_accel": 0.5, "max_yaw_accel": 1.0,
     "max_yaw_rate": 1.0, "max_speed": 1.5, "min_speed": -0.2},
    {"radius": 0.2, "max_accel": 1.0},
    {"radius": 0.2},
])
def test_commands_stay_within_the_limits(robot):
    sc = dict(POSTS, obstacles=[{"position": [9.5, 2.4], "velocity": [-0.5, 0.0],
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
            if math.isfinite(m.max_accel_mps2):
                assert math.hypot(*(a - prev)) <= m.max_accel_mps2 * dt + 1e-9


def test_barn_world_at_1_mps():
    from pathfuse.io.gazebo import read_gazebo_world
    from pathfuse.studies.barn import (
        BARN_BOUNDS,
        BarnConfig,
        _scenario,
        find_worlds,
        jackal_robot,
    )

    robot = dict(jackal_robot("diff-drive"), max_speed=1.0)
    cfg = BarnConfig(str(BARN), resolution=0.05, robot=robot)
    for w in find_worlds(BARN, [0, 43]):
        ep = simulate(_scenario(cfg, w, "0" * 16), planner="mppi")
        assert ep.status is Status.SUCCESS, (w.index, ep.message)
        assert ep.min_static_clearance_m > 0.0
        grid = read_gazebo_world(w.world, cfg.resolution, bounds=BARN_BOUNDS)
        pos = np.asarray(ep.positions)
        # the chords between ticks, less the arcs' sagitta (see tests/test_barn.py)
        chord = np.hypot(*np.diff(pos, axis=0).T)
        turn = np.abs((np.diff(ep.headings) + math.pi) % (2 * math.pi) - math.pi)
        sag = 1.01 * chord * turn / 8.0 + 1e-9
        assert np.all(segment_clearances(grid, pos) >= cfg.robot_radius_m - sag)


def test_head_on_disc_swerves_where_standing_still_is_hit():
    sc = dict(HALL, obstacles=[{"position": [10.5, 2.5], "velocity": [-0.5, 0.0],
                                "radius": 0.3}])
    # standing in the disc's way: it walks into the robot
    w = World(dict(sc, robot=DIFF))
    w.reset(0)
    while True:
        _, term, trunc, info = w.step((0.0, 0.0))
        if term or trunc:
            break
    assert info["event"] == "collision" and info["collision"] == 0
    for robot in (DIFF, HOLO):
        ep = simulate(sc, planner="mppi", robot=robot)
        assert ep.status is Status.SUCCESS, ep.message
        assert ep.min_obstacle_distance_m > 0.0
        assert np.abs(ep.positions[:, 1] - 2.5).max() > 0.3  # it stepped aside


@pytest.mark.parametrize("dwell_s", [0.0, 1.5])  # below and at the escape's own dwell
def test_lane_escape_scores_against_the_current_path(dwell_s):
    # the lane escape's settings follow every new path: after a replan its path search
    # (seg_max_m) is the new path's, not the first one's; the escape's dwell critic stays
    from pathfuse.planners.controllers.dwa_escape import ESCAPE_DWELL_S

    w = World(dict(HALL, robot=DIFF))
    w.reset(0)
    m = w.robot
    pb = Problem.create(w.scenario.grid, w.scenario.start, w.scenario.goal, m.radius_m, robot=m)
    ctrl = start_online(get_planner("mppi"), pb, MPPIParams(dwell_s=dwell_s), w.dt,
                        m.max_speed_mps)
    first = ctrl.f_escape.seg_max_m
    ctrl._set_path(np.array([[1.5, 2.5], [7.5, 2.5], [13.5, 2.5]]))  # 6 m segments
    assert ctrl.f.seg_max_m == pytest.approx(6.0) != first
    assert ctrl.f_escape.seg_max_m == ctrl.f.seg_max_m
    assert ctrl.f_escape.dwell_s == max(dwell_s, ESCAPE_DWELL_S)


def test_track_from_the_last_point_reads_only_the_path():
    """``_track`` asked from the path's last point takes its last segment; it read the
    point after the last before (out of bounds, unchecked in compiled code), which its
    source run by CPython shows as an IndexError."""
    from pathfuse.planners.controllers.mppi_kernel import _track

    pts = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.5]])
    cum = np.array([0.0, 1.0, 1.0 + np.hypot(1.0, 0.5)])
    for j in (1, 2):
        got = _track.py_func(2.1, 0.4, pts, cum, j, 0, 5.0, 5.0)  # its source, bounds checked
        assert got == _track(2.1, 0.4, pts, cum, j, 0, 5.0, 5.0)
        assert got[0] == 1 and got[2] == 1.0  # the last segment, at its end
