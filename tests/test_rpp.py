"""Regulated Pure Pursuit (pathfuse.planners.controllers.rpp), the path followers' controller on a
diff-drive robot: its geometry, episodes along corridors and on a BARN world, and the
holonomic walk left exactly as it was."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

import pathfuse
from pathfuse import simulate
from pathfuse.costmap import make_costmap
from pathfuse.grid import GridMap
from pathfuse.planners.controllers.follow import FollowController, ReplanController
from pathfuse.planners.controllers.rpp import (
    CARROT_MARGIN_M,
    MODE_PURSUIT,
    MODE_ROTATE,
    RppSettings,
    carrot_is_clear,
    carrot_point,
    closest_progress,
    lookahead_distance,
    pack_settings,
    point_at,
    pursuit_curvature,
    regulated_speed,
    rpp_step,
)
from pathfuse.planners.params import PursuitParams
from pathfuse.planners.registry import get_planner, make_params
from pathfuse.planners.run import start_online
from pathfuse.problem import Problem
from pathfuse.result import ConfigError, Status
from pathfuse.robot import RobotModel
from pathfuse.world import World, load_scenario

FOLLOWERS = ["astar", "astar-replan", "thetastar", "lazy-thetastar", "astar-smooth", "shortest",
             "jps"]
BARN = Path(__file__).parent / "data" / "barn"
DT = 0.1


def _cum(path: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])


def _cfg(robot: RobotModel | None = None, **kw: object) -> RppSettings:
    rb = robot or RobotModel.diff_drive(radius_m=0.2, max_speed_mps=1.0)
    return pack_settings(PursuitParams(**kw), rb, DT, rb.max_speed_mps)


# an empty 10 m x 10 m map with its origin at (-5, -5): the robot near (0, 0)
FREE = np.zeros((100, 100), dtype=np.bool_)
ORG = -5.0


def _step(path, x, y, th, v0=0.0, w0=0.0, i0=0, s0=0.0, occ=FREE, cfg=None):
    path = np.ascontiguousarray(path, dtype=np.float64)
    cfg = _cfg() if cfg is None else cfg
    cm = make_costmap(occ, 0.2, origin=(ORG, ORG), resolution_m=0.1)
    return rpp_step(path, _cum(path), cm, cfg, x, y, th, v0, w0, i0, s0)


def _cm(occ):
    return make_costmap(occ, 0.2, origin=(ORG, ORG), resolution_m=0.1)


# ----------------------------------------------------------------------------- geometry
@pytest.mark.parametrize("radius", [0.5, 1.0, 3.0])
@pytest.mark.parametrize("side", [1.0, -1.0])
def test_curvature_to_a_carrot_on_a_known_circle(radius, side):
    # the robot at the origin heading +x; the circle through it, centred at (0, side R)
    for phi in (0.05, 0.5, 1.2, 2.0):
        xr, yr = radius * math.sin(phi), side * radius * (1.0 - math.cos(phi))
        assert pursuit_curvature(xr, yr) == pytest.approx(side / radius, rel=1e-12)
    # the kernel on a path along that circle: the carrot is on it, 0.6 m from the robot
    # (v0 = 0.4 m/s x 1.5 s), and the command drives the circle's curvature
    t = np.linspace(0.0, 2.0, 4001)
    path = np.column_stack([radius * np.sin(t), side * radius * (1.0 - np.cos(t))])
    v, w, _, s, mode, cx, cy = _step(path, 0.0, 0.0, 0.0, v0=0.4)
    assert mode == MODE_PURSUIT and v > 0 and s == 0.0
    assert w / v == pytest.approx(side / radius, rel=1e-4)
    phi = 2.0 * math.asin(0.3 / radius)  # a chord of 0.6 m
    assert math.hypot(cx - radius * math.sin(phi), cy - side * radius * (1 - math.cos(phi))) \
        < 1e-5


def test_a_yaw_rate_beyond_the_window_lowers_the_speed_not_the_curvature():
    # a carrot on a circle of radius 0.5 at 0.6 m: kappa = 2; from rest the yaw rate may reach
    # only alpha dt = 0.4 rad/s this tick, so v = 0.2 keeps omega / v = kappa
    t = np.linspace(0.0, 2.0, 4001)
    path = np.column_stack([0.5 * np.sin(t), 0.5 * (1.0 - np.cos(t))])
    v, w, *_ = _step(path, 0.0, 0.0, 0.0, v0=0.4, w0=0.0)
    assert w == pytest.approx(0.4) and v == pytest.approx(0.2)
    # with the yaw rate already turning, the curvature's own speed (regulated: R 0.5 of 0.9)
    v, w, *_ = _step(path, 0.0, 0.0, 0.0, v0=0.4, w0=1.0)
    assert v == pytest.approx(0.5 / 0.9) and w == pytest.approx(2.0 * v)


@pytest.mark.parametrize("bearing, sign", [(math.pi, 1.0), (-1.75, -1.0), (2.2, 1.0)])
def test_rotate_in_place_for_a_carrot_behind(bearing, sign):
    path = np.array([[0.0, 0.0], [3.0 * math.cos(bearing), 3.0 * math.sin(bearing)]])
    v, w, _, _, mode, *_ = _step(path, 0.0, 0.0, 0.0, v0=0.5)
    assert mode == MODE_ROTATE and v == 0.0 and w == sign * 2.0  # the yaw-rate limit
    # the yaw rate is one from which the turn can still stop at the carrot's heading
    fast = RobotModel.diff_drive(radius_m=0.2, max_speed_mps=1.0, max_yaw_rate_radps=10.0)
    v, w, _, _, mode, *_ = _step(path, 0.0, 0.0, 0.0, cfg=_cfg(fast))
    e = abs(math.atan2(math.sin(bearing), math.cos(bearing)))
    assert mode == MODE_ROTATE and v == 0.0
    assert w == pytest.approx(sign * min(e / DT, math.sqrt(2.0 * 4.0 * e)), rel=1e-12)
    # below the threshold (45 degrees): no turn on the spot
    path = np.array([[0.0, 0.0], [1.0, 0.7]])
    assert _step(path, 0.0, 0.0, 0.0)[4] == MODE_PURSUIT


def test_progress_is_monotone_and_searched_in_a_window_ahead():
    # a U-turn: out along y = 0, back along y = 0.6
    path = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 0.6], [0.0, 0.6]])
    cum = _cum(path)
    # next to the way back at the start: the window keeps the progress on the way out
    i, s = closest_progress(path, cum, 0.5, 0.55, 0, 0.0, 1.5)
    assert (i, s) == (0, pytest.approx(0.5))
    i, s = closest_progress(path, cum, 0.5, 0.55, 0, 0.0, 100.0)  # no window: across the loop
    assert i == 2 and s == pytest.approx(6.1)
    # never back: a robot behind its progress keeps it
    assert closest_progress(path, cum, 0.2, 0.0, 0, 1.0, 1.5) == (0, 1.0)
    # along a walk that wobbles back and forth, the progress only grows
    s, i = 0.0, 0
    rng = np.random.default_rng(3)
    for k in range(60):
        u = 6.6 * k / 59 + rng.uniform(-0.4, 0.4)
        x, y = point_at(path, cum, 0, max(u, 0.0))
        i2, s2 = closest_progress(path, cum, x + rng.uniform(-0.1, 0.1), y, i, s, 1.5)
        assert s2 >= s and i2 >= i
        i, s = i2, s2
    assert s == pytest.approx(cum[-1], abs=0.45)


def test_lookahead_is_clipped_and_the_carrot_interpolated_on_the_path():
    assert lookahead_distance(0.1, 1.5, 0.3, 0.9) == 0.3
    assert lookahead_distance(0.4, 1.5, 0.3, 0.9) == pytest.approx(0.6)
    assert lookahead_distance(-0.4, 1.5, 0.3, 0.9) == pytest.approx(0.6)
    assert lookahead_distance(2.0, 1.5, 0.3, 0.9) == 0.9
    # the carrot: where the path beyond the closest point leaves the circle of radius L
    # around the robot (0.05 m off the path here)
    path = np.array([[-2.0, 0.0], [0.5, 0.0], [4.0, 0.0]])
    for v0, la in ((0.0, 0.3), (0.4, 0.6), (2.0, 0.9)):
        *_, cx, cy = _step(path, -1.0, 0.05, 0.0, v0=v0, i0=0, s0=0.5)
        assert (cx, cy) == (pytest.approx(-1.0 + math.sqrt(la * la - 0.05 ** 2)), 0.0)
    cum = _cum(path)
    assert carrot_point(path, cum, 0, 1.0, -1.0, 0.05, 0.6) == pytest.approx(
        (-1.0 + math.sqrt(0.6 ** 2 - 0.05 ** 2), 0.0))
    # a robot further from the path than L: the closest point itself
    assert carrot_point(path, cum, 0, 1.0, -1.0, 0.5, 0.3) == (-1.0, 0.0)
    # less path left than the lookahead: the carrot is the path's end
    _, _, i, s, _, cx, cy = _step(path, 3.7, 0.0, 0.0, v0=2.0, i0=1, s0=4.5)
    assert (i, s, cx, cy) == (1, pytest.approx(5.7), 4.0, 0.0)


def test_speed_regulated_by_curvature_proximity_and_a_floor():
    rs = regulated_speed
    far = 100.0  # goal distance
    args = (DT, 0.9, 0.25, 0.3, 0.6, 0.05)  # dt, rmin, floor, proximity, approach, min approach
    assert rs(1.0, 0.0, 1.0, far, 2.0, *args) == 1.0
    assert rs(1.0, 1.0 / 3.0, 1.0, far, 2.0, *args) == 1.0  # radius 3 m: no scaling
    assert rs(1.0, 1.0 / 0.45, 1.0, far, 2.0, *args) == pytest.approx(0.5)  # radius 0.45 m
    assert rs(1.0, 0.0, 0.15, far, 2.0, *args) == pytest.approx(0.5)  # gap 0.15 m of 0.3
    assert rs(1.0, 1.0 / 0.6, 0.15, far, 2.0, *args) == pytest.approx(0.5)  # the lower one
    assert rs(1.0, 0.0, 0.03, far, 2.0, *args) == 0.25  # the floor
    assert rs(1.0, 50.0, -0.01, far, 2.0, *args) == 0.25
    assert rs(0.2, 0.0, 0.03, far, 2.0, *args) == 0.2  # never above the top speed
    # off: regulated_min_radius_m = 0, proximity_distance_m = 0
    assert rs(1.0, 5.0, 0.01, far, 2.0, DT, 0.0, 0.25, 0.0, 0.6, 0.05) == 1.0
    # in the kernel: a straight path 0.1 m from a wall, the disc's exact gap regulates
    occ = np.zeros((100, 100), dtype=np.bool_)
    occ[:, 53:] = True  # a wall at x = 0.3
    path = np.array([[0.0, -3.0], [0.0, 3.0]])
    v, w, *_ = _step(path, 0.0, 0.0, math.pi / 2, v0=0.3, occ=occ,
                     cfg=_cfg(proximity_distance_m=0.3))
    assert v == pytest.approx(1.0 * 0.1 / 0.3) and w == pytest.approx(0.0, abs=1e-12)
    v, w, *_ = _step(path, 0.0, 0.0, math.pi / 2, v0=0.3, occ=occ)  # the default, 0.1 m
    assert v == pytest.approx(0.5)  # the acceleration window: 0.3 + 2 m/s^2 x 0.1 s


def test_approach_slows_down_to_the_goal():
    rs = regulated_speed
    args = (DT, 0.9, 0.25, 0.3, 0.6, 0.05)
    assert rs(1.0, 0.0, 1.0, 0.3, 2.0, *args) == pytest.approx(0.5)  # 0.3 of 0.6 m
    assert rs(1.0, 0.0, 1.0, 0.01, 2.0, *args) == pytest.approx(0.05)  # the least approach
    assert rs(1.0, 0.0, 1.0, 0.002, 2.0, *args) == pytest.approx(0.02)  # not past the goal
    # braking: never faster than sqrt(2 a d), even without the approach scaling
    assert rs(2.0, 0.0, 1.0, 0.2, 1.0, DT, 0.9, 0.25, 0.3, 0.0, 0.05) \
        == pytest.approx(math.sqrt(0.4))
    # an episode onto a goal with a tight tolerance: it arrives without passing it
    sc = {"map": {"rows": ["." * 60] * 10, "resolution": 0.1}, "start": [0.5, 0.5],
          "goal": [5.0, 0.5], "goal_tolerance": 0.01,
          "robot": {"model": "diff-drive", "radius": 0.2, "max_speed": 1.0, "heading": 0.0}}
    ep = simulate(sc, planner="astar")
    assert ep.status is Status.SUCCESS, ep.message
    assert ep.positions[:, 0].max() <= 5.0 + 0.01
    v = ep.commands[:, 0]
    d = 5.0 - ep.positions[:-1, 0]
    assert np.all(v <= np.sqrt(2.0 * 2.0 * np.maximum(d, 0.0)) + 1e-9)


def _frame(px, py, x, y, th):
    c, s = math.cos(th), math.sin(th)
    return c * (px - x) + s * (py - y), -s * (px - x) + c * (py - y)


def test_an_arc_through_a_wall_shortens_the_lookahead():
    # a path turning right around a block's corner: the arc to the far carrot cuts the block
    occ = np.zeros((100, 100), dtype=np.bool_)
    occ[50:60, 45:50] = True  # the block [-0.5, 0] x [0, 1]
    path = np.array([[0.25, -1.5], [0.25, 0.25], [-1.0, 0.25]])
    x, y, th = 0.25, -0.6, math.pi / 2
    far = _step(path, x, y, th, v0=1.0, occ=occ, cfg=_cfg(clear_carrot=False))
    near = _step(path, x, y, th, v0=1.0, occ=occ)
    assert math.hypot(far[5] - x, far[6] - y) == pytest.approx(0.9)
    assert not carrot_is_clear(_cm(occ), x, y, th, *_frame(far[5], far[6], x, y, th),
                               0.785, 0.2)
    assert math.hypot(near[5] - x, near[6] - y) < 0.9
    assert carrot_is_clear(_cm(occ), x, y, th, *_frame(near[5], near[6], x, y, th),
                           0.785, 0.2)
    assert near[4] == MODE_PURSUIT and near[0] > 0


def test_a_carrot_on_a_path_without_slack_is_kept_off_the_wall():
    # a path along a wall at exactly the radius: the carrot is moved a hair away
    occ = np.zeros((100, 100), dtype=np.bool_)
    occ[:, 53:] = True  # a wall at x = 0.3
    path = np.array([[0.1, -3.0], [0.1, 3.0]])
    *_, cx, cy = _step(path, 0.1 - 1e-4, 0.0, math.pi / 2, v0=0.2, occ=occ)
    assert cx == pytest.approx(0.1 - 1e-6 * 0.1 - CARROT_MARGIN_M, abs=1e-9)
    assert cy == pytest.approx(0.3, abs=1e-3)


# ----------------------------------------------------------------------------- episodes
def _rows(occ: np.ndarray) -> list[str]:
    return ["".join("#" if c else "." for c in r) for r in occ[::-1]]


def _slalom() -> dict:
    occ = np.zeros((30, 90), dtype=bool)  # 9 m x 3 m at 0.1 m, row 0 at the bottom
    occ[:20, 20:23] = True  # fins from the bottom, the top, the bottom
    occ[10:, 45:48] = True
    occ[:20, 70:73] = True
    return {"map": {"rows": _rows(occ), "resolution": 0.1}, "start": [0.5, 0.5],
            "goal": [8.5, 0.5], "time_limit": 60}


def _ell() -> dict:
    occ = np.ones((60, 60), dtype=bool)
    occ[2:12, 2:50] = False  # a 1 m corridor along the bottom, then up
    occ[2:58, 40:50] = False
    return {"map": {"rows": _rows(occ), "resolution": 0.1}, "start": [0.8, 0.7],
            "goal": [4.5, 5.3], "time_limit": 60}


def _drive(doc: dict, planner: str, params: dict | None = None):
    """The episode by hand (World, start_online, command): the controller and the
    per-tick commands."""
    sc = load_scenario(doc)
    spec = get_planner(planner)
    world = World(sc)
    obs = world.reset()
    rb = world.robot
    ctrl = start_online(spec, Problem.create(sc.grid, sc.start, sc.goal, sc.robot.radius_m,
                                             robot=rb),
                        make_params(spec, params), sc.dt, sc.robot.max_speed_mps)
    event = None
    for _ in range(sc.n_steps):
        obs, term, trunc, info = world.step(ctrl.command(obs))
        if term or trunc:
            event = info["event"]
            break
    return ctrl, event


@pytest.mark.parametrize("planner", FOLLOWERS)
@pytest.mark.parametrize("corridor, clearance", [("slalom", 0.0), ("ell", 0.0),
                                                 ("slalom", 0.05), ("ell", 0.05)])
def test_a_diff_drive_robot_follows_a_corridor_to_the_goal(planner, corridor, clearance):
    """Without a safety margin (the grid path runs along the walls at exactly the radius)
    and with one (the global A* keeps away from the walls where it can)."""
    doc = _slalom() if corridor == "slalom" else _ell()
    doc["robot"] = {"model": "diff-drive", "radius": 0.25, "max_speed": 1.0,
                    "clearance": clearance}
    ep = simulate(doc, planner=planner)
    assert ep.status is Status.SUCCESS, ep.message
    assert ep.min_static_clearance_m >= 0.0
    # the follower's own commands: the shield never had to replace one
    assert ep.shield_counts["asked"] == ep.n_ticks, ep.shield_counts
    # never standing still: every command moves or turns the robot
    v, w = ep.commands.T
    assert np.all((np.abs(v) > 1e-3) | (np.abs(w) > 1e-3))
    # and over every second the robot gets on (a robot that turns on the spot at a corner
    # still moves within a second)
    moved = np.hypot(*(ep.positions[10:] - ep.positions[:-10]).T)
    assert moved.min() > 0.05
    ctrl, event = _drive(doc, planner)
    assert event == "reached" and ctrl.acts_unicycle
    modes = ctrl._rpp.modes  # type: ignore[attr-defined]
    assert modes[MODE_PURSUIT] > 0


def test_the_followers_answer_unicycle_commands_only_on_a_diff_drive_robot():
    doc = _ell()
    doc["robot"] = {"model": "diff-drive", "radius": 0.25}
    ctrl, _ = _drive(doc, "astar-replan")
    assert isinstance(ctrl, ReplanController) and ctrl.acts_unicycle
    doc["robot"] = {"model": "holonomic", "radius": 0.25}
    ctrl, _ = _drive(doc, "astar")
    assert isinstance(ctrl, FollowController) and not ctrl.acts_unicycle
    assert ctrl._rpp is None  # type: ignore[attr-defined]
    for name in FOLLOWERS:
        # RPP runs (and is compiled) only for a diff-drive robot online: an offline plan or
        # a holonomic episode does not pay for its compilation
        ctrl = get_planner(name).controller
        assert rpp_step in ctrl.diff_drive_kernels()
        assert rpp_step not in ctrl.kernels()


def test_astar_replan_follows_each_replanned_path_on_a_diff_drive_robot():
    hall = ["." * 15] * 5
    doc = {"map": {"rows": hall}, "start": [1.5, 2.5], "goal": [13.5, 2.5],
           "robot": {"model": "diff-drive", "radius": 0.2, "max_speed": 1.0,
                     "sensing_radius": 3.0},
           "time_limit": 40,
           "obstacles": [{"position": [7.5, 2.5], "velocity": [0, 0], "radius": 0.6}]}
    ep = simulate(doc, planner={"name": "astar-replan", "params": {"replan_period_s": 0.5}})
    assert ep.status is Status.SUCCESS, ep.message
    assert len(ep.path_updates) > 1 and ep.min_obstacle_distance_m > 0


# ----------------------------------------------------------------------------- holonomic
def _walk(path: np.ndarray, step: float, corners: bool, n: int) -> np.ndarray:
    """The followers' holonomic walk, written again: each tick the point ``step`` further
    along the path (ending a tick on a corner when ``corners``)."""
    cum = _cum(path)
    out = [path[0]]
    s = 0.0
    for _ in range(n):
        t = min(s + step, cum[-1])
        if corners:
            nxt = np.searchsorted(cum, s, side="right")
            if nxt < len(cum) - 1 and cum[nxt] < t:
                t = cum[nxt]
        s = t
        out.append(np.array(point_at(path, cum, 0, s)))
    return np.array(out)


@pytest.mark.parametrize("planner", ["astar", "thetastar", "shortest"])
def test_a_holonomic_robot_walks_the_path_as_before(planner):
    doc = _slalom()
    # the safety shield off: the controller's own walk (the shield, on by default, may
    # replace a move that grazes a fin; it does the same with or without this follower)
    doc["robot"] = {"radius": 0.25, "max_speed": 1.0, "shield": False}
    ep = simulate(doc, planner=planner)
    assert ep.status is Status.SUCCESS, ep.message
    path = np.asarray(ep.global_path)
    walk = _walk(path, 1.0 * DT, planner != "astar", ep.n_ticks)
    assert np.allclose(ep.positions, walk, rtol=0.0, atol=1e-9)
    # the follower's parameters change nothing for it, shielded or not
    for shield in (False, True):
        doc["robot"]["shield"] = shield
        ep = simulate(doc, planner=planner)
        other = simulate(doc, planner={"name": planner, "params": {
            "max_lookahead_m": 2.0, "proximity_distance_m": 0.0, "clear_carrot": False}})
        assert np.array_equal(other.positions, ep.positions)
        assert np.array_equal(other.commands, ep.commands)


def test_parameters_checked_and_plan_unchanged():
    g = GridMap.from_rows(["....", ".##.", "...."], resolution=0.5)
    with pytest.raises(ConfigError, match=r"^astar\.max_lookahead_m: must be >= "
                                          r"min_lookahead_m \(0\.3\), got 0\.1$"):
        pathfuse.plan(g, (0.25, 0.25), (1.75, 1.25), max_lookahead_m=0.1)
    with pytest.raises(ConfigError, match=r"^thetastar\.lookahead_time_s: must be a number > 0"):
        pathfuse.plan(g, (0.25, 0.25), (1.75, 1.25), planner="thetastar", lookahead_time_s=0)
    a = pathfuse.plan(g, (0.25, 0.25), (1.75, 1.25))
    b = pathfuse.plan(g, (0.25, 0.25), (1.75, 1.25), max_lookahead_m=3.0, clear_carrot=False)
    assert np.array_equal(a.path, b.path) and a.length == b.length
    for name in FOLLOWERS:
        fields = {f.name for f in dataclasses.fields(get_planner(name).params_cls)}
        assert {f.name for f in dataclasses.fields(PursuitParams)} <= fields
        for f in dataclasses.fields(PursuitParams):
            assert "no effect on a holonomic robot" in f.metadata["param"].help


# ----------------------------------------------------------------------------- BARN
def test_astar_reaches_the_goal_of_a_barn_world_at_1_mps():
    """World 43 at 1 m/s: the previous follower (an arc-length pointer at full speed,
    converted to (v, omega)) cut a corner, ended next to a cylinder and stood there until
    the time limit; the pursuit follower reaches the goal, and the shield never steps in."""
    from pathfuse.studies.barn import BarnConfig, _scenario, find_worlds

    (w,) = find_worlds(BARN, [43])
    cfg = BarnConfig(str(BARN), resolution=0.05)
    sc = _scenario(cfg, w, "0" * 16)
    sc["robot"]["max_speed"] = 1.0
    assert sc["robot"]["model"] == "diff-drive" and sc["robot"]["radius"] == 0.333
    for planner in ("astar", "shortest"):
        ep = simulate(sc, planner=planner)
        assert ep.status is Status.SUCCESS, (planner, ep.message)
        assert ep.min_static_clearance_m >= 0.0
        assert ep.time_to_goal_s < 30.0
        assert ep.shield_counts["asked"] >= 0.99 * ep.n_ticks, ep.shield_counts
