"""Every registered planner keeps the same contract, offline and online.

The planners are taken from the registry, so a planner added later is checked
here without editing this file.  Offline (:func:`pathfuse.plan`): success and
safety on the paper's maps, correct end points, the statuses of bad queries
and exhausted budgets, the robot radius, unknown parameters, determinism, and
the bookkeeping of :class:`PlanResult`.  Online (:func:`pathfuse.simulate`):
reaching the goal on small static maps, the bookkeeping of an
:class:`Episode` among a crossing disc, and one set of parameter defaults for
both.
"""

from __future__ import annotations

import dataclasses
import math
import re
import time
from pathlib import Path

import numpy as np
import pytest

from pathfuse import Budget, ConfigError, GridMap, Status, plan, simulate
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.metrics import collision_free, evaluate, path_length
from pathfuse.planners.controllers.fusion import FusionParams
from pathfuse.planners.globals.astar import route
from pathfuse.planners.registry import get_global_planner, get_planner, make_params, planner_names
from pathfuse.planners.run import warm
from pathfuse.problem import Problem

NAMES = planner_names()
ONLINE = [n for n in NAMES if get_planner(n).online]
SEEDS = range(10)

BOX = GridMap.from_rows([   # the goal (5.5, 2.5) is walled in
    "..........",
    "...#####..",
    "...#...#..",
    "...#####..",
    "..........",
])
CORRIDOR = GridMap(np.zeros((5, 40), dtype=bool))


def check_bookkeeping(r, name):
    assert r.planner == name
    assert math.isfinite(r.time_s) and r.time_s > 0
    assert r.path.ndim == 2 and r.path.shape[1] == 2 and np.all(np.isfinite(r.path))
    if r.path.shape[0] >= 2:
        assert r.length == pytest.approx(float(np.hypot(*np.diff(r.path, axis=0).T).sum()))


def counts_expansions(name):
    """Whether ``Budget.max_iterations`` caps the global search (grid A*) rather than the
    controller's moves."""
    ctrl = get_planner(name).controller
    return ctrl is not None and ctrl.search_budget


def test_all_builtin_planners_are_registered():
    assert {"astar", "astar-replan", "apf", "fusion", "ref6", "ref7"} <= set(NAMES)
    # every built-in planner runs offline and online
    for name in ("astar", "astar-replan", "apf", "fusion", "ref6", "ref7", "dwa", "jps"):
        spec = get_planner(name)
        assert spec.offline and spec.online and spec.capabilities() == ("offline", "online")
    assert get_planner("astar-follow").name == "astar"


@pytest.mark.parametrize("name", NAMES)
def test_paper_maps(name):
    spec = get_planner(name)
    wins = 0
    for seed in SEEDS:
        g = paper_map(seed)
        r = plan(g, PAPER_START, PAPER_GOAL, planner=name)
        m = evaluate(g, r)
        check_bookkeeping(r, name)
        assert m["collision_free"], (name, seed)
        # the paper's start and goal are cell centres, so even grid A* starts and ends on them
        assert r.path[0].tolist() == list(PAPER_START), (name, seed)
        if spec.has_global_plan:
            # the map connects start and goal: a global planner must get there
            assert r.success, (name, seed, r.message)
        else:
            # a purely local planner may be caught in a local minimum, nothing else
            assert r.status in (Status.SUCCESS, Status.LOCAL_MINIMUM), (name, seed)
        if r.success:
            wins += 1
            assert r.path[-1].tolist() == list(PAPER_GOAL), (name, seed)
    assert wins >= 1


@pytest.mark.parametrize("name", NAMES)
def test_end_points_off_cell_centres(name):
    g = GridMap(np.zeros((8, 12), dtype=bool), resolution=0.5, origin=(-1.0, 2.0))
    s, e = (-0.8, 2.3), (4.6, 5.45)
    r = plan(g, s, e, planner=name)
    assert r.success and evaluate(g, r)["collision_free"]
    if "cells" in r.info:  # a grid path (astar, astar-replan) runs between cell centres
        np.testing.assert_allclose(r.path, g.cell_to_world(r.info["cells"]))
        np.testing.assert_allclose(r.path[[0, -1]], [[-0.75, 2.25], [4.75, 5.25]])
    else:
        assert r.path[0].tolist() == list(s) and r.path[-1].tolist() == list(e)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("start,goal,status", [
    ((4.5, 1.5), (0.5, 0.5), Status.START_OCCUPIED),
    ((0.5, 0.5), (4.5, 1.5), Status.GOAL_OCCUPIED),
    ((-0.1, 0.5), (0.5, 0.5), Status.START_OUT_OF_BOUNDS),
    ((0.5, 0.5), (10.0, 0.5), Status.GOAL_OUT_OF_BOUNDS),
    ((0.5, 5.0), (0.5, 0.5), Status.START_OUT_OF_BOUNDS),
])
def test_bad_queries(name, start, goal, status):
    r = plan(BOX, start, goal, planner=name)
    assert r.status is status and r.planner == name
    assert r.path.shape == (0, 2) and not r


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("start,goal,status", [
    ((0.1, 0.5), (9.5, 4.5), Status.START_OCCUPIED),   # the disc overlaps the map's edge
    ((0.5, 0.5), (9.5, 4.85), Status.GOAL_OCCUPIED),
    ((2.75, 2.5), (9.5, 4.5), Status.START_OCCUPIED),  # the disc overlaps a square
    ((0.5, 0.5), (8.25, 2.0), Status.GOAL_OCCUPIED),
])
def test_robot_disc_blocked_at_start_or_goal(name, start, goal, status):
    r = plan(BOX, start, goal, planner=name, robot_radius_m=0.3)
    assert r.status is status and r.planner == name and r.path.shape == (0, 2)
    # the same points are free for a point robot
    assert plan(BOX, start, goal, planner=name, robot_radius_m=0.0).status not in (
        Status.START_OCCUPIED, Status.GOAL_OCCUPIED)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("start,goal,blocked", [
    ((0.3, 2.5), (9.5, 2.5), Status.START_OCCUPIED),
    ((0.5, 2.5), (9.7, 2.5), Status.GOAL_OCCUPIED),
    ((0.5, 2.5), (5.5, 4.7), Status.GOAL_OCCUPIED),
])
def test_robot_disc_touching_the_edge_is_either_blocked_or_planned(name, start, goal, blocked):
    # the robot disc at the start or goal touches the map's edge (clearance exactly the
    # radius): the one problem check decides, for every planner alike, whether the query
    # is blocked; a query it accepts on this open map must be planned to the goal
    g = GridMap(np.zeros((5, 10), dtype=bool))
    r = plan(g, start, goal, planner=name, robot_radius_m=0.3)
    accepted = Problem.create(g, start, goal, robot_radius_m=0.3).failure() is None
    if not accepted:
        assert r.status is blocked and r.path.shape == (0, 2)
    else:
        assert r.status is Status.SUCCESS, (name, r.message)
        if "cells" not in r.info:
            assert r.path[0].tolist() == list(start) and r.path[-1].tolist() == list(goal)


@pytest.mark.parametrize("name", NAMES)
def test_robot_radius_keeps_clearance_from_squares_and_the_edge(name):
    spec = get_planner(name)
    radius = 0.3
    for seed in range(4):
        g = paper_map(seed)
        r = plan(g, PAPER_START, PAPER_GOAL, planner=name, robot_radius_m=radius)
        check_bookkeeping(r, name)
        assert len(r.path) >= 2, (name, seed, r.message)
        assert collision_free(g, r.path, robot_radius_m=radius), (name, seed)
        x0, y0, x1, y1 = g.bounds
        edge = np.min([r.path[:, 0] - x0, x1 - r.path[:, 0], r.path[:, 1] - y0,
                       y1 - r.path[:, 1]])
        assert edge >= radius, (name, seed)
        if spec.has_global_plan:
            assert r.success, (name, seed, r.message)


@pytest.mark.parametrize("name", NAMES)
def test_unreachable_goal(name):
    spec = get_planner(name)
    warm(spec)  # keep a cold numba cache out of the wall-clock check
    t0 = time.perf_counter()
    r = plan(BOX, (0.5, 0.5), (5.5, 2.5), planner=name)
    wall = time.perf_counter() - t0
    check_bookkeeping(r, name)
    assert not r.success
    if spec.has_global_plan:
        assert r.status is Status.NO_PATH and r.path.shape == (0, 2)
    else:
        assert r.status in (Status.LOCAL_MINIMUM, Status.NO_PATH)
        assert evaluate(BOX, r)["collision_free"]
    assert wall < 2.0


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("cap", [1, 3])
def test_iteration_cap(name, cap):
    if name in ("shortest", "jps"):
        # one expansion (the start) never reaches the goal, even here; but the start's
        # jump east (jps) or sight line (shortest) finds the goal, expanded second
        cap = 1
    r = plan(CORRIDOR, (0.5, 2.5), (38.5, 2.5), planner=name, budget=Budget(max_iterations=cap))
    check_bookkeeping(r, name)
    assert r.status is Status.MAX_ITERATIONS
    # the cap counts expansions for grid A*, force steps for the potential-field planners
    assert (r.expansions if counts_expansions(name) else r.iterations) == cap
    if name in ("shortest", "jps"):
        # the visibility graph of this corridor has no corner: the start sees the goal, so
        # two expansions suffice; on a map with obstacles the cap stops it likewise
        g = paper_map(0)
        full = plan(g, PAPER_START, PAPER_GOAL, planner=name)
        assert full.success and full.expansions > cap
        r = plan(g, PAPER_START, PAPER_GOAL, planner=name, budget=Budget(max_iterations=cap))
        assert r.status is Status.MAX_ITERATIONS and r.expansions == cap
    assert evaluate(CORRIDOR, r)["collision_free"]


@pytest.mark.parametrize("name", NAMES)
def test_unknown_parameter(name):
    spec = get_planner(name)
    fields = ", ".join(spec.defaults())
    want = (rf"^{re.escape(name)}\.no_such_knob: unknown parameter "
            rf"\(parameters: {re.escape(fields)}\)$")
    with pytest.raises(ConfigError, match=want):
        plan(CORRIDOR, (0.5, 2.5), (38.5, 2.5), planner=name, no_such_knob=1)
    # the robot radius is part of the problem, never a planner parameter
    assert "robot_radius_m" not in spec.defaults()
    with pytest.raises(ConfigError, match=r"^robot_radius_m: must be a finite number >= 0, "
                                          r"got -0\.5$"):
        plan(CORRIDOR, (0.5, 2.5), (38.5, 2.5), planner=name, robot_radius_m=-0.5)


@pytest.mark.parametrize("name", NAMES)
def test_defaults_build_and_are_frozen(name):
    spec = get_planner(name)
    p = spec.params_cls()
    field = next(iter(spec.defaults()), None)
    if field is not None:
        with pytest.raises(AttributeError):
            setattr(p, field, getattr(p, field))


@pytest.mark.parametrize("name", NAMES)
def test_deterministic(name):
    g = paper_map(11)
    a = plan(g, PAPER_START, PAPER_GOAL, planner=name)
    b = plan(g, PAPER_START, PAPER_GOAL, planner=name)
    assert a.status is b.status and np.array_equal(a.path, b.path)
    assert a.iterations == b.iterations and a.expansions == b.expansions


# ============================================================================== online
# Small static scenarios on which every planner - plain APF included - reaches the goal.
REACHABLE = {
    "corridor": {"map": {"rows": ["........", "........", "........"]},
                 "start": [0.5, 1.5], "goal": [7.5, 1.5], "robot": {"radius": 0.2}},
    "block": {"map": {"rows": ["..........", "..........", "....##....", "....##....",
                               "..........", ".........."]},
              "start": [0.5, 0.5], "goal": [9.5, 5.5], "robot": {"radius": 0.2}},
    "offset": {"map": {"rows": ["............", "............", "......#.....", "......#.....",
                                "............", "............"],
                       "resolution": 0.5, "origin": [-1.0, 2.0]},
               "start": [-0.7, 2.3], "goal": [4.6, 4.7], "robot": {"radius": 0.15}},
}
# A wall in front of the start: plain APF has a local minimum there, the others must pass.
WALL = {"map": {"rows": ["..........", "..........", "...#......", "...#......", "...#......",
                         ".........."]},
        "start": [0.5, 3.5], "goal": [9.5, 3.5], "robot": {"radius": 0.2}}
# One disc crossing the straight line from start to goal.
CROSSING = {"map": {"rows": ["............"] * 5},
            "start": [0.5, 2.5], "goal": [11.5, 2.5], "robot": {"radius": 0.2},
            "time_limit": 30,
            "obstacles": [{"position": [6.0, 0.5], "velocity": [0.0, 0.4], "radius": 0.3}]}


def check_episode(ep, name, sc):
    """The bookkeeping of an :class:`Episode`, whatever its outcome."""
    spec = get_planner(name)
    assert isinstance(ep.status, Status)
    assert ep.planner == spec.name
    assert ep.params == spec.defaults()
    n, k = ep.n_ticks, len(sc.get("obstacles", []))
    dt = ep.scenario.dt
    assert ep.times.shape == (n + 1,) and ep.times[0] == 0.0
    np.testing.assert_allclose(np.diff(ep.times), dt)
    assert ep.positions.shape == (n + 1, 2) and np.all(np.isfinite(ep.positions))
    assert ep.positions[0].tolist() == list(sc["start"])
    assert ep.velocities.shape == (n, 2) and ep.plan_times_s.shape == (n,)
    assert ep.obstacle_positions.shape == (n + 1, k, 2) and ep.sensed.shape == (n + 1, k)
    assert ep.obstacle_radii.shape == (k,)
    # the robot moved with the recorded (clipped) velocities
    np.testing.assert_allclose(ep.positions[1:], ep.positions[:-1] + ep.velocities * dt,
                               atol=1e-12)
    speed = ep.scenario.robot.max_speed_mps
    assert np.all(np.hypot(*ep.velocities.T) <= speed * (1 + 1e-12))
    assert ep.path_length_m == pytest.approx(path_length(ep.positions))
    assert ep.min_distance_m == min(ep.min_static_clearance_m, ep.min_obstacle_distance_m)
    assert (ep.min_obstacle_distance_m == math.inf) == (k == 0)
    assert ep.reached == (ep.status is Status.SUCCESS)
    if ep.status is Status.SUCCESS:
        assert ep.time_to_goal_s == ep.times[-1] and n > 0
        a, b, goal = ep.positions[-2], ep.positions[-1], np.array(sc["goal"])
        t = np.clip(np.dot(goal - a, b - a) / max(np.dot(b - a, b - a), 1e-300), 0.0, 1.0)
        assert np.hypot(*(a + t * (b - a) - goal)) <= ep.scenario.goal_tolerance + 1e-9
    else:
        assert ep.time_to_goal_s is None
    if ep.status is Status.COLLISION:
        assert ep.collision_with is not None and ep.min_distance_m < 0
        if ep.collision_with == "static":
            assert ep.min_static_clearance_m < 0
        else:
            assert 0 <= ep.collision_with < k and ep.min_obstacle_distance_m < 0
    else:
        assert ep.collision_with is None and ep.min_distance_m >= 0
    if spec.has_global_plan and ep.status not in (Status.NO_PATH, Status.START_OCCUPIED,
                                                  Status.GOAL_OCCUPIED):
        # the first global path is the one plan() would follow on the static map
        g = ep.scenario.grid
        if spec.uses_astar:
            want = route(g, sc["start"], sc["goal"], sc["robot"]["radius"])
        else:  # another global planner: the waypoints of its plan on the static map (an
            # any-angle planner's are what plan() returns)
            from pathfuse.planners.globals.builtin import run_global

            pb = Problem.create(g, sc["start"], sc["goal"], sc["robot"]["radius"])
            want = run_global(spec.global_planner, pb).waypoints
            if get_global_planner(spec.global_planner).taut:
                np.testing.assert_array_equal(
                    want, plan(g, sc["start"], sc["goal"], planner=name,
                               robot_radius_m=sc["robot"]["radius"]).path)
        np.testing.assert_array_equal(ep.global_path, want)
        assert ep.path_updates[0][0] == 0
    elif not spec.has_global_plan:
        assert ep.global_path is None and ep.path_updates == []
    assert ep.message


@pytest.mark.parametrize("name", ONLINE)
@pytest.mark.parametrize("where", sorted(REACHABLE))
def test_online_reaches_the_goal_on_static_maps(name, where):
    sc = REACHABLE[where]
    ep = simulate(sc, planner=name)
    check_episode(ep, name, sc)
    assert ep.status is Status.SUCCESS, (name, where, ep.message)
    assert ep.min_static_clearance_m >= 0
    # the same scenario and seed give the same episode, bit for bit
    again = simulate(sc, planner=name)
    assert again.status is ep.status and np.array_equal(again.positions, ep.positions)


@pytest.mark.parametrize("name", ONLINE)
def test_online_local_minimum_only_for_plain_apf(name):
    ep = simulate(WALL, planner=name)
    check_episode(ep, name, WALL)
    assert ep.min_static_clearance_m >= 0
    if get_planner(name).has_global_plan:
        assert ep.status is Status.SUCCESS, (name, ep.message)
    else:
        assert ep.status in (Status.SUCCESS, Status.LOCAL_MINIMUM), (name, ep.message)


@pytest.mark.parametrize("name", ONLINE)
def test_online_crossing_disc_bookkeeping(name):
    ep = simulate(CROSSING, planner=name)
    check_episode(ep, name, CROSSING)
    assert ep.status in set(Status)
    assert ep.status in (Status.SUCCESS, Status.COLLISION, Status.TIMEOUT,
                         Status.LOCAL_MINIMUM), (name, ep.message)
    # whatever happened with the disc, the robot never touched the static map
    assert ep.min_static_clearance_m >= 0 or ep.collision_with == "static"
    assert ep.sensed.any()   # the disc came within the sensing radius


def test_plan_and_simulate_use_the_same_fusion_defaults():
    spec = get_planner("fusion")
    assert spec.params_cls is FusionParams
    defaults = dataclasses.asdict(FusionParams())
    assert spec.params_cls() == FusionParams() and spec.defaults() == defaults
    # what plan() builds without parameters, and what simulate() records
    assert make_params(spec) == FusionParams()
    ep = simulate(REACHABLE["corridor"], planner="fusion")
    assert ep.params == defaults
    assert simulate(REACHABLE["corridor"]).params == defaults   # the default planner
    # one override, the other defaults kept, offline and online alike
    ep = simulate(REACHABLE["corridor"], planner={"name": "fusion", "params": {"r1_m": 1.5}})
    assert ep.params == {**defaults, "r1_m": 1.5}
    assert make_params(spec, {"r1_m": 1.5}) == FusionParams(r1_m=1.5)


@pytest.mark.parametrize("name", ONLINE)
def test_plan_and_simulate_use_the_same_defaults(name):
    spec = get_planner(name)
    ep = simulate(REACHABLE["corridor"], planner=name)
    assert ep.params == dataclasses.asdict(make_params(spec)) == spec.defaults()


_NO_COMPILE_AFTER_WARM = r"""
import sys
from numba.core.registry import CPUDispatcher
import pathfuse
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.planners.registry import get_planner, planner_names
from pathfuse.planners.run import warm

def signatures():
    out = {}
    for name, mod in list(sys.modules.items()):
        if name.startswith("pathfuse"):
            for v in list(vars(mod).values()):
                if isinstance(v, CPUDispatcher):
                    out[v.py_func.__module__ + "." + v.__name__] = len(v.signatures)
    return out

names = planner_names()
for n in names:
    warm(get_planner(n))
before = signatures()
for n in names:
    for seed in (0, 1):
        for radius in (0.0, 0.2):
            r = pathfuse.plan(paper_map(seed), PAPER_START, PAPER_GOAL, planner=n,
                              robot_radius_m=radius)
            assert r.status.name in ("SUCCESS", "LOCAL_MINIMUM"), (n, seed, radius, r.message)
after = signatures()
print(" ".join(sorted(k for k, v in after.items() if v != before.get(k, 0))))
"""


def test_warm_up_compiles_every_signature_a_plan_uses(tmp_path):
    """The warm-up is what keeps compilation out of the planners' timings: after
    ``warm(spec)``, planning on a real GridMap (whose arrays are read-only, a different
    numba type from a fresh array) must not compile or load any kernel again.  Run in a
    fresh process, since this one has compiled everything already."""
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", _NO_COMPILE_AFTER_WARM], capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    lines = out.stdout.strip().splitlines()
    assert lines == [] or lines == [""], f"kernels compiled after the warm-up: {lines}"


_NO_COMPILE_IN_A_DECISION = r"""
import sys
import traceback
from pathlib import Path
from numba.core.dispatcher import Dispatcher
import pathfuse
import pathfuse.tier  # its hook first: the spy below wraps it
from pathfuse.robot import RobotModel

timed = []
numba_compile = Dispatcher._compile_for_args

def spy(self, *args, **kws):
    # numba found no code of this kernel for these types in the process (or its fast path
    # matched none): a new overload is a compile or a load from its cache; inside
    # Controller.command, the episode's timed decision (not the warm-up episode's)
    before = len(self.overloads)
    out = numba_compile(self, *args, **kws)
    stack = traceback.extract_stack()
    if len(self.overloads) > before and \
            any(f.name == "command" and f.filename.endswith("planners/base.py") for f in stack) \
            and not any(f.name == "_warm_episode" for f in stack):
        timed.append(CURRENT[0] + ": " + self.py_func.__qualname__)
    return out

Dispatcher._compile_for_args = spy
CURRENT = [""]
scenario = Path(sys.argv[1])
robots = {"holonomic": RobotModel(radius_m=0.2, max_speed_mps=1.0, sensing_radius_m=3.0),
          "diff-drive": RobotModel.diff_drive(radius_m=0.2, max_speed_mps=1.0,
                                              sensing_radius_m=3.0)}
n = sys.argv[2]
for kind, robot in robots.items():
    CURRENT[0] = f"{n} {kind}"
    pathfuse.simulate(scenario, planner=n, robot=robot)
print("\n".join(sorted(set(timed))))
"""


def _online_planners() -> list[str]:
    from pathfuse.planners.registry import get_planner, planner_names

    return [n for n in planner_names() if get_planner(n).online]


@pytest.mark.parametrize("name", _online_planners())
def test_no_kernel_compiles_inside_an_episode_s_decision(name):
    """The same for episodes: ``simulate`` warms what its planner runs online (on its
    robot model) before the first tick, so no tick's decision time holds a compile, among
    moving discs on either robot model (mppi's lane escape compiled inside the first
    episode's ticks: a ``max_plan_time_s`` of 5 s)."""
    import subprocess
    import sys

    head_on = Path(__file__).resolve().parents[1] / "examples" / "scenarios" / "head_on.yaml"
    # a process per planner: a kernel another planner loaded first would hide its own gap
    out = subprocess.run([sys.executable, "-c", _NO_COMPILE_IN_A_DECISION, str(head_on), name],
                         capture_output=True, text=True, timeout=900)
    assert out.returncode == 0, out.stderr[-2000:]
    lines = out.stdout.strip().splitlines()
    assert lines == [], f"compiled inside a decision: {lines}"
