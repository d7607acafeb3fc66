"""Recovery behaviours (:mod:`pathfuse.planners.recovery`): detection, the cycle, each
behaviour's commands, the switch, and a robot that stood before a door."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pathfuse import Status, simulate
from pathfuse.planners.recovery import RecoveryMonitor
from pathfuse.result import ConfigError
from pathfuse.robot import RobotModel


def _feed(m: RecoveryMonitor, positions, heading=0.0, bearing=None, relax=lambda s: False):
    out = []
    for p in positions:
        out.append(m.step(np.asarray(p, float), heading, lambda: bearing, relax))
    return out


def test_no_recovery_while_the_robot_moves():
    m = RecoveryMonitor(0.1, diff_drive=True, can_reverse=False)
    out = _feed(m, [(0.05 * i, 0.0) for i in range(400)])  # 0.5 m/s for 40 s
    assert all(c is None for c in out)
    assert sum(m.counts.values()) == 0


def test_a_stall_runs_the_cycle_clear_spin_wait():
    relaxed = []

    def relax(s):
        relaxed.append(s)
        return True

    m = RecoveryMonitor(0.1, diff_drive=True, can_reverse=False, max_yaw_rate=2.0,
                        max_yaw_accel=4.0)
    # standing still: the first detection after stall_s (5 s) clears the critics
    out = _feed(m, [(0.0, 0.0)] * 50, relax=relax)
    assert relaxed == [] and all(c is None for c in out)
    out = _feed(m, [(0.0, 0.0)] * 2, relax=relax)
    assert relaxed == [3.0] and m.counts["clear"] == 1
    assert all(c is None for c in out)  # the controller acts, with relaxed critics
    # still standing: the next detection spins towards the path's bearing, a quarter turn
    # at most, on the spot (v = 0, omega of the bearing's sign)
    cmds = []
    for _ in range(200):
        c = m.step(np.zeros(2), 0.0, lambda: 2.5, relax)
        if c is not None:
            cmds.append(c)
        if m.counts["spin"]:
            break
    assert m.counts["spin"] == 1 and cmds and cmds[0][0] == 0.0 and cmds[0][1] > 0
    assert m.target == pytest.approx(math.pi / 2)
    # a robot that cannot reverse waits (zero command) as its third behaviour
    heading = 0.0
    seen_wait = False
    for _ in range(400):
        c = m.step(np.zeros(2), heading, lambda: 2.5, relax)
        if c is not None and m.active == "spin":
            heading += c[1] * 0.1  # the spin turns the robot
        if m.active == "wait":
            seen_wait = True
            assert c is not None and not c.any()
    assert seen_wait and m.counts["wait"] >= 1 and m.counts["back_up"] == 0


def test_a_controller_without_critics_skips_clear():
    m = RecoveryMonitor(0.1, diff_drive=False, can_reverse=True)
    assert m.behaviours == ("clear", "back_up")
    # came from the left, then stuck: backing up goes back the way it came
    path = [(0.05 * i, 0.0) for i in range(20)] + [(0.95, 0.0)] * 60
    out = _feed(m, path)
    assert m.counts["clear"] == 0 and m.counts["back_up"] == 1
    c = next(c for c in out if c is not None)
    assert c[0] < 0 and c[1] == pytest.approx(0.0) and np.hypot(*c) == pytest.approx(0.15)


def test_an_oscillation_is_detected():
    m = RecoveryMonitor(0.1, diff_drive=False, can_reverse=True)
    # back and forth over 0.6 m at 0.6 m/s: moving all the time, never getting anywhere
    xs = np.abs(((np.arange(300) * 0.06) % 1.2) - 0.6)
    _feed(m, [(x, 0.0) for x in xs])
    assert m.counts["back_up"] >= 1


def test_progress_restarts_the_cycle():
    m = RecoveryMonitor(0.1, diff_drive=False, can_reverse=True)
    _feed(m, [(0.0, 0.0)] * 60)
    assert m.next_k >= 1
    _feed(m, [(0.05 * i, 0.0) for i in range(60)])  # got 3 m away
    assert m.next_k == 0


def test_the_switch():
    assert RobotModel().recovery and RobotModel.diff_drive().recovery
    with pytest.raises(ConfigError, match=r"robot\.recovery"):
        RobotModel(recovery="yes")  # type: ignore[arg-type]
    assert RobotModel.from_dict({"recovery": False}).recovery is False


# a wall with one door: 0.75 m wide for a 0.4 m robot
DOOR = {"map": {"rows": ["#" * 20] + ["." * 20] * 3 + ["#" * 9 + "..." + "#" * 8]
                + ["." * 20] * 3 + ["#" * 20], "resolution": 0.25},
        "start": [2.5, 0.6], "goal": [2.5, 1.6], "time_limit": 40}


def _door(recovery: bool):
    robot = {"model": "diff-drive", "radius": 0.2, "max_speed": 1.0, "recovery": recovery}
    # an obstacle critic 60 times dwa's default: every sample towards the door costs more
    # than standing in front of it
    return simulate(dict(DOOR, robot=robot),
                    planner={"name": "dwa", "params": {"obstacle_weight": 30.0}})


def test_clearing_the_critics_gets_a_robot_through_the_door_it_stood_before():
    stuck = _door(False)
    assert stuck.status is Status.LOCAL_MINIMUM  # the episode's 10 s stall rule
    assert np.ptp(stuck.positions[-50:], axis=0).max() < 0.01  # standing, not wandering
    ep = _door(True)
    assert ep.status is Status.SUCCESS, ep.message
    assert ep.collision_with is None and ep.min_static_clearance_m > 0
    # the default critics go through without a recovery
    robot = {"model": "diff-drive", "radius": 0.2, "max_speed": 1.0}
    assert simulate(dict(DOOR, robot=robot), planner="dwa").status is Status.SUCCESS
