"""The fusion in velocity space on a diff-drive robot
(pathfuse.planners.controllers.fusion_window)."""

from __future__ import annotations

import numpy as np

from pathfuse import Status, simulate
from pathfuse.metrics import segment_clearances
from pathfuse.planners.registry import get_planner, make_params
from pathfuse.planners.run import start_online
from pathfuse.problem import Problem
from pathfuse.world import World
from pathfuse.world.generate import generate_scenarios

DIFF = {"model": "diff-drive"}


def _scenarios(n):
    return generate_scenarios(n, moving=0, speed_range=(0.3, 0.8), seed=0, robot=DIFF,
                              name="t")


def _controller(sc, **params):
    world = World(sc)
    world.reset(0)
    spec = get_planner("fusion")
    pb = Problem.create(sc.grid, sc.start, sc.goal, sc.robot.radius, robot=world.robot)
    return start_online(spec, pb, make_params(spec, params), world.dt, world.max_speed)


def test_the_window_is_used_only_on_a_diff_drive_robot_and_can_be_switched_off():
    sc = _scenarios(1)[0]
    assert _controller(sc)._window is not None
    assert _controller(sc, velocity_space=False)._window is None
    holo = sc.replace(robot=sc.robot.__class__(radius=sc.robot.radius))
    assert _controller(holo)._window is None


def test_streamline_looks_ahead_without_moving_the_fusion():
    """The local path is Algorithm 2's next moves; computing it leaves the fusion's state
    (its walk, progress and escape bookkeeping) as it was."""
    sc = _scenarios(1)[0]
    ctrl = _controller(sc)
    world = World(sc)
    obs = world.reset(0)
    for _ in range(5):
        obs, *_ = world.step(ctrl.command(obs))
    ctrl.act(obs)
    n, buf, state = ctrl.n, ctrl.buf[:ctrl.n].copy(), ctrl.state.copy()
    line = ctrl._streamline(obs)
    assert ctrl.n == n and np.array_equal(ctrl.buf[:n], buf)
    assert np.array_equal(ctrl.state, state)
    assert line.shape[0] == ctrl._window.steps + 2
    assert line[0].tolist() == obs.position.tolist()
    steps = np.hypot(*np.diff(line[1:], axis=0).T)
    assert steps.max() <= ctrl.step_m + 1e-9  # one move of max_speed x dt each
    assert segment_clearances(sc.grid, line[1:]).min() >= sc.robot.radius


def test_static_maps_reached_without_collision():
    """The paper's map family with a diff-drive robot and no disc: the fusion in velocity
    space never collides and reaches the goal in 9 of the first 10 scenarios (7 of 10 with
    a 5 cm safety margin: it leaves the field fewer ways through these 1 m cells; scenario
    1 needs the stall recovery); the conversion of the move, for comparison, never
    collides either."""
    reached = 0
    for index, sc in enumerate(_scenarios(10)):
        ep = simulate(sc, planner="fusion", seed=index)
        assert ep.status is not Status.COLLISION and ep.min_static_clearance_m >= 0.0
        reached += ep.status is Status.SUCCESS
        off = simulate(sc, planner={"name": "fusion", "params": {"velocity_space": False}},
                       seed=index)
        assert off.status is not Status.COLLISION
    assert reached >= 9


def test_recovery_replans_from_where_the_robot_stands():
    sc = _scenarios(2)[1]
    ctrl = _controller(sc)
    world = World(sc)
    obs = world.reset(1)
    while True:
        obs, term, trunc, info = world.step(ctrl.command(obs))
        if term or trunc:
            break
    assert info["event"] == "reached"
    assert ctrl._window.recoveries >= 1
