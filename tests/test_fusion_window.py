"""The fusion in velocity space on a diff-drive robot
(pathfuse.planners.controllers.fusion_window)."""

from __future__ import annotations

import numpy as np

from pathfuse import Status, simulate
from pathfuse.metrics import segment_clearances
from pathfuse.planners.registry import get_planner, make_params
from pathfuse.planners.run import start_online
from pathfuse.problem import Problem
from pathfuse.robot import RobotModel
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
    pb = Problem.create(sc.grid, sc.start, sc.goal, sc.robot.radius_m, robot=world.robot)
    return start_online(spec, pb, make_params(spec, params), world.dt, world.max_speed)


def test_the_window_is_used_only_on_a_diff_drive_robot_and_can_be_switched_off():
    sc = _scenarios(1)[0]
    assert _controller(sc)._window is not None
    assert _controller(sc, velocity_space=False)._window is None
    holo = sc.replace(robot=RobotModel(radius_m=sc.robot.radius_m))
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
    assert segment_clearances(sc.grid, line[1:]).min() >= sc.robot.radius_m


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


def _head_on(speed=0.6):
    """A disc walks head on along the robot's straight route in a 5 m wide hall."""
    return {"map": {"rows": ["." * 15] * 5, "resolution": 1.0},
            "start": [1.5, 2.5], "goal": [13.5, 2.5],
            "robot": {"radius": 0.2, "max_speed": 1.0, "sensing_radius": 3.0, **DIFF},
            "dt": 0.1, "time_limit": 40,
            "obstacles": [{"position": [10.5, 2.5], "velocity": [-speed, 0.0],
                           "radius": 0.3}]}


def _drive(sc, seed=0, **params):
    """Run the fusion tick by tick; per tick (disc sensed, in-place turns so far, MPPI
    ticks so far), and the episode's end."""
    from pathfuse.world.scenario import load_scenario

    sc = load_scenario(sc)
    ctrl = _controller(sc, **params)
    world = World(sc)
    obs = world.reset(seed)
    ticks = []
    info: dict = {}
    for _ in range(world.n_steps):
        sensed = len(obs.obstacles) > 0
        obs, terminated, truncated, info = world.step(ctrl.command(obs))
        ticks.append((sensed, ctrl._window.rotations, ctrl._window.sequenced))
        if terminated or truncated:
            break
    return ctrl, ticks, info


def test_among_discs_mppi_sequences_track_the_local_path_and_the_robot_never_spins():
    """Ours: while a disc is sensed the fusion's local path is tracked by MPPI's sequences,
    and the robot does not stand to turn on the spot (how it was walked into: its local
    path swung as discs came near and it spun while they arrived).  The head-on disc is
    passed with room to spare."""
    ctrl, ticks, info = _drive(_head_on())
    assert info["event"] == "reached"
    among = [i for i, t in enumerate(ticks) if t[0]]
    assert among, "the disc was never sensed"
    for i in among:
        before = ticks[i - 1] if i else (False, 0, 0)
        assert ticks[i][1] == before[1]  # no turn on the spot on a tick with a disc
        assert ticks[i][2] == before[2] + 1  # decided by the sequences
    assert ticks[-1][2] == len(among)
    ep = simulate(_head_on(), planner="fusion")
    assert ep.status is Status.SUCCESS and ep.min_obstacle_distance_m >= 0.3


def test_among_discs_the_window_can_be_kept():
    ctrl, ticks, info = _drive(_head_on(), among_discs="window")
    assert ticks[-1][2] == 0
    assert info["event"] != "collision" or not info.get("at_fault", False)


def test_the_global_path_is_replanned_around_a_sensed_disc():
    """Ours (as dwa): while a disc is sensed, A* again from the robot every
    replan_period_s with the disc's cells blocked; 0 switches it off."""
    ep = simulate(_head_on(0.3), planner="fusion")
    assert len(ep.path_updates) >= 2
    tick, path = ep.path_updates[1]
    disc = ep.obstacle_positions[tick][0]
    radius = ep.obstacle_radii[0] + 0.2
    assert np.hypot(path[:, 0] - disc[0], path[:, 1] - disc[1]).min() >= radius
    off = simulate(_head_on(0.3), planner={"name": "fusion",
                                            "params": {"replan_period_s": 0}})
    assert len(off.path_updates) == 1


def test_among_discs_the_same_seed_gives_the_same_episode():
    a = simulate(_head_on(), planner={"name": "fusion", "params": {"seed": 3}})
    b = simulate(_head_on(), planner={"name": "fusion", "params": {"seed": 3}})
    assert np.array_equal(a.positions, b.positions)


def test_progress_indices_always_point_into_the_current_path():
    """After a replan the walked points' progress indices (read by the escape's rejoin
    search as indices into the path, unchecked in numba) refer to the new path."""
    from pathfuse.world.scenario import load_scenario

    sc = load_scenario(_head_on(0.3))
    ctrl = _controller(sc)
    world = World(sc)
    obs = world.reset(0)
    replanned = 0
    for _ in range(world.n_steps):
        before = ctrl.pts
        obs, terminated, truncated, _ = world.step(ctrl.command(obs))
        replanned += ctrl.pts is not before
        assert 0 <= ctrl.kbuf[:ctrl.n].min() and ctrl.kbuf[:ctrl.n].max() < ctrl.pts.shape[0]
        assert 0 <= ctrl.state[0] < ctrl.pts.shape[0]
        if terminated or truncated:
            break
    assert replanned >= 1


def test_entering_among_discs_the_sequences_start_from_the_present_command(monkeypatch):
    """MPPI's warm start is the optimum of its last call; when the fusion comes back among
    discs after a stretch without, that optimum is seconds old: the sequences then start
    from the command the robot is executing."""
    from pathfuse.planners.controllers.mppi import MPPIController

    seen = []
    orig = MPPIController._choose

    def spy(self, x, y, th, c0, c1, *a):
        seen.append((self.nominal.copy(), c0, c1))
        return orig(self, x, y, th, c0, c1, *a)

    monkeypatch.setattr(MPPIController, "_choose", spy)
    ctrl, ticks, info = _drive(_head_on())
    assert seen
    nominal, c0, c1 = seen[0]
    assert np.all(nominal[:, 0] == c0) and np.all(nominal[:, 1] == c1)
    assert c0 > 0.0  # the robot was driving when the disc came into range


def test_a_lane_is_not_kept_at_the_cost_of_a_long_detour():
    """replan_lane_detour_m (ours): a disc walking across the mouth of the near gap in a
    wall blocks that gap with its 3 s lane, not with itself; out of the lane the path goes
    round by the far gap (some 14 m longer).  With the limit (2 m, the default) the path
    around the disc alone, through the near gap, is kept; without it (0) the detour."""
    from pathfuse.grid import GridMap
    from pathfuse.planners.controllers.replan import replan_around_discs

    # 12 x 12 cells of 1 m (first row at the top): a wall at y = 5..6 with gaps at x = 2..3
    # and x = 10..11
    g = GridMap.from_rows(["." * 12] * 6 + ["##.#######.#"] + ["." * 12] * 5)
    pb = Problem.create(g, (2.5, 1.5), (2.5, 9.5), 0.2)
    p = make_params(get_planner("fusion"), {})
    dpos, dvel, drad = np.array([[5.0, 4.2]]), np.array([[-1.0, 0.0]]), np.array([0.3])

    def length(pts):
        return float(np.hypot(*np.diff(pts, axis=0).T).sum())

    rep = {}
    near = replan_around_discs(pb, 2.5, 1.5, dpos, drad, p, personal_m=p.personal_m,
                               dvel=dvel, lane_s=p.replan_lane_s,
                               lane_detour_m=p.replan_lane_detour_m, report=rep)
    assert rep["detour"] and length(near) < 9.0 and near[:, 0].max() < 4.0
    rep = {}
    far = replan_around_discs(pb, 2.5, 1.5, dpos, drad, p, personal_m=p.personal_m,
                              dvel=dvel, lane_s=p.replan_lane_s, lane_detour_m=0.0, report=rep)
    assert not rep["detour"] and length(far) > length(near) + 10.0 and far[:, 0].max() > 9.0
