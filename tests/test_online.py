"""Online planners and the episode runner: outcomes, replay, safety checked independently."""

from __future__ import annotations

import dataclasses
import inspect
import json
import math

import numpy as np
import pytest

import pathfuse
from pathfuse import ConfigError, GridMap, Status
from pathfuse.field.forces import repulsive_force
from pathfuse.field.repulsion import disc_repulsion
from pathfuse.planners.base import Controller
from pathfuse.planners.controllers.apf import APFParams
from pathfuse.planners.controllers.follow import ReplanParams
from pathfuse.planners.globals.astar import route
from pathfuse.planners.registry import (
    PlannerSpec,
    get_planner,
    make_params,
    planner_names,
    register,
    register_function,
)
from pathfuse.planners.run import start_online
from pathfuse.problem import Problem
from pathfuse.world import (
    Observation,
    ScenarioError,
    World,
    load_scenario,
    run_episode,
    simulate,
)
from pathfuse.world.generate import generate_scenarios

PLANNERS = ["fusion", "apf", "astar", "astar-replan", "ref6", "ref7", "dwa", "mppi"]
HALL = ["." * 15] * 5


def head_on(**kw):
    doc = {"map": {"rows": HALL}, "start": [1.5, 2.5], "goal": [13.5, 2.5],
           "robot": {"radius": 0.2, "max_speed": 1.0, "sensing_radius": 3.0},
           "dt": 0.1, "time_limit": 40,
           "obstacles": [{"position": [10.5, 2.5], "velocity": [-0.5, 0.0], "radius": 0.3}]}
    doc.update(kw)
    return doc


# ----------------------------------------------------------------------------- independent checks
def _seg_box(a, b, box):
    """Segment-to-box distance by dense sampling of the segment (an independent oracle)."""
    t = np.linspace(0.0, 1.0, 201)[:, None]
    p = a + t * (b - a)
    x0, y0, x1, y1 = box
    dx = np.maximum(np.maximum(x0 - p[:, 0], 0), p[:, 0] - x1)
    dy = np.maximum(np.maximum(y0 - p[:, 1], 0), p[:, 1] - y1)
    return float(np.hypot(dx, dy).min())


def _independent_min_gaps(ep):
    """Least gap to the discs and to the static map, sampling every tick 50 times."""
    sc = ep.scenario
    r = sc.robot.radius_m
    t = np.linspace(0.0, 1.0, 51)[:, None, None]
    p = ep.positions[:-1][None] + t * (ep.positions[1:] - ep.positions[:-1])[None]  # (S, T, 2)
    disc = math.inf
    if ep.obstacle_radii.size:
        q0, q1 = ep.obstacle_positions[:-1], ep.obstacle_positions[1:]
        q = q0[None] + t[..., None] * (q1 - q0)[None]                               # (S,T,K,2)
        d = np.linalg.norm(p[:, :, None, :] - q, axis=-1) - ep.obstacle_radii - r
        disc = float(d.min())
    g = sc.grid
    x0, y0, x1, y1 = g.bounds
    pts = p.reshape(-1, 2)
    static = float(np.min([pts[:, 0] - x0, x1 - pts[:, 0], pts[:, 1] - y0, y1 - pts[:, 1]]))
    res = g.resolution
    for rr, cc in np.argwhere(g.occupied):
        bx, by = g.origin[0] + cc * res, g.origin[1] + rr * res
        dx = np.maximum(np.maximum(bx - pts[:, 0], 0), pts[:, 0] - bx - res)
        dy = np.maximum(np.maximum(by - pts[:, 1], 0), pts[:, 1] - by - res)
        static = min(static, float(np.hypot(dx, dy).min()))
    return disc, static - r


def _drive(doc, planner, params=None, seed=None):
    """An episode driven by hand through the public API (World + start_online + act);
    returns the controller and the robot's positions.  There is no stall test: compare
    with episodes that end at the goal, in a collision or at the time limit."""
    sc = load_scenario(doc)
    spec = get_planner(planner)
    world = World(sc)
    obs = world.reset(seed)
    ctrl = start_online(spec, Problem.create(sc.grid, sc.start, sc.goal, sc.robot.radius_m),
                        make_params(spec, params), sc.dt, sc.robot.max_speed_mps)
    positions = [obs.position]
    while ctrl.failure is None:
        obs, term, trunc, _ = world.step(ctrl.act(obs))
        positions.append(obs.position)
        if term or trunc:
            break
    return ctrl, np.array(positions)


# ----------------------------------------------------------------------------- registry
def test_registry_names_and_parameter_errors():
    # one registry: every built-in planner runs online (the any-angle ones follow their path)
    any_angle = ["astar-smooth", "thetastar", "lazy-thetastar", "shortest", "jps"]
    assert sorted(n for n in planner_names() if get_planner(n).online) == sorted(
        PLANNERS + any_angle)
    assert all(get_planner(n).offline for n in PLANNERS)
    with pytest.raises(ConfigError, match=r"^planner.name: unknown planner 'dstar'"):
        simulate(head_on(), planner="dstar")
    with pytest.raises(ConfigError, match=r"^planner.params.swerve: must be a number >= 0"):
        simulate(head_on(), planner={"name": "fusion", "params": {"swerve": -1}})
    with pytest.raises(ConfigError, match=r"^planner.params.replan_period_s"):
        simulate(head_on(), planner={"name": "astar-replan", "params": {"replan_period_s": 0}})
    with pytest.raises(ConfigError, match=r"^planner.extra: unknown key"):
        simulate(head_on(), planner={"name": "apf", "extra": 1})
    # parameters that no longer exist are unknown, naming the key
    with pytest.raises(ConfigError, match=r"^planner.params.escape_ticks: unknown parameter"):
        simulate(head_on(), planner={"name": "fusion", "params": {"escape_ticks": 20}})
    with pytest.raises(ConfigError, match=r"^planner.params.robot_radius_m: unknown parameter"):
        simulate(head_on(), planner={"name": "apf", "params": {"robot_radius_m": 0.2}})


def test_the_old_astar_follow_name_runs_astar_and_the_episode_records_astar():
    assert get_planner("astar-follow") is get_planner("astar")
    old = simulate(head_on(), planner="astar-follow")
    new = simulate(head_on(), planner="astar")
    assert old.planner == new.planner == "astar"
    assert np.array_equal(old.positions, new.positions)
    assert old.to_dict()["planner"] == "astar"


def test_an_offline_only_plugin_cannot_be_simulated():
    def straight(grid, start, goal, params, budget):  # pragma: no cover - never called
        raise AssertionError("an offline plug-in must not be run online")

    spec = register_function("straight", straight, APFParams, "a straight line")
    assert spec.offline and not spec.online
    with pytest.raises(ScenarioError, match=r"^planner.name: 'straight' only plans offline"):
        simulate(head_on(), planner="straight")
    problem = Problem.create(GridMap.from_rows(HALL), (1.5, 2.5), (13.5, 2.5), 0.2)
    with pytest.raises(ConfigError, match="only plans offline"):
        start_online(spec, problem, APFParams(), 0.1, 1.0)


def test_pathfuse_exports_simulate():
    assert pathfuse.simulate is simulate


WALLS = ["............", "....#.......", "....#...#...", "....#...#...", "........#..."]
POSTS = ["............", "....#...#...", "............", "......#.....", "............"]


@pytest.mark.parametrize("planner,rows", [(p, WALLS) for p in PLANNERS if p != "apf"]
                         + [(p, POSTS) for p in PLANNERS])
def test_every_planner_reaches_the_goal_without_moving_obstacles(planner, rows):
    doc = {"map": {"rows": rows}, "start": [1.5, 2.5], "goal": [10.5, 2.5],
           "robot": {"radius": 0.25}}
    ep = simulate(doc, planner=planner)
    assert ep.status is Status.SUCCESS, ep.message
    assert np.hypot(*(ep.positions[-1] - [10.5, 2.5])) <= 0.25 + 1e-9
    disc, static = _independent_min_gaps(ep)
    assert static >= 0.0
    assert ep.min_static_clearance_m == pytest.approx(static, abs=2e-3)
    speeds = np.hypot(*ep.velocities.T)
    assert speeds.max() <= 1.0 + 1e-9


# ----------------------------------------------------------------------------- the head-on case
def test_head_on_astar_collides_and_fusion_passes():
    follow = simulate(head_on(), planner="astar")
    assert follow.status is Status.COLLISION and follow.collision_with == 0
    disc, _ = _independent_min_gaps(follow)
    assert disc < 0.0                     # an independent look at the trajectories agrees

    fusion = simulate(head_on(), planner="fusion")
    assert fusion.status is Status.SUCCESS, fusion.message
    disc, static = _independent_min_gaps(fusion)
    assert disc > 0.0 and static >= 0.0
    assert fusion.min_obstacle_distance_m == pytest.approx(disc, abs=1e-3)
    assert fusion.min_obstacle_distance_m <= disc + 1e-12   # exact minimum <= samples
    # it stepped aside: its largest lateral offset is about a disc's width
    assert np.abs(fusion.positions[:, 1] - 2.5).max() > 0.5


def test_head_on_pure_radial_repulsion_cannot_pass():
    # without the tangential part and the dodge (the paper's eq. 6 alone) the robot can
    # only back off, pushed by the disc until it is pinned against the wall behind it (the
    # controller alone: the safety shield, which would move it aside at the last moment, off)
    doc = head_on(robot={"radius": 0.2, "max_speed": 1.0, "sensing_radius": 3.0,
                         "shield": False})
    ep = simulate(doc, planner={"name": "fusion", "params": {"swerve": 0.0, "dodge": False}})
    assert ep.status is Status.COLLISION
    assert np.abs(ep.positions[:, 1] - 2.5).max() < 1e-9
    # with the shield the robot is standing when the disc reaches it: not its fault
    ep = simulate(head_on(), planner={"name": "fusion",
                                      "params": {"swerve": 0.0, "dodge": False}})
    assert ep.status is Status.COLLISION and ep.collision_at_fault is False


@pytest.mark.parametrize("planner", ["astar-replan", "apf", "ref6", "ref7"])
def test_head_on_other_planners_avoid_the_disc(planner):
    ep = simulate(head_on(), planner=planner)
    assert ep.status is Status.SUCCESS, ep.message
    assert _independent_min_gaps(ep)[0] > 0.0


# ----------------------------------------------------------------------------- replay
def _walkers():
    return {"map": {"paper": {"seed": 2}}, "start": [1, 1], "goal": [11, 11],
            "time_limit": 30,
            "obstacles": [
                {"random_walk": {"position": [6, 6], "speed": 0.6, "seed": 1}, "radius": 0.3},
                {"random_walk": {"position": [4, 8], "speed": 0.5}, "radius": 0.3},
                {"position": [9, 3], "velocity": [0.3, 0.5], "radius": 0.3},
                {"waypoints": [[2, 6], [9, 6]], "speed": 0.5, "radius": 0.25},
            ]}


@pytest.mark.parametrize("planner", PLANNERS)
def test_same_scenario_and_seed_replay_bit_for_bit(planner):
    a = simulate(_walkers(), planner=planner, seed=11)
    b = simulate(_walkers(), planner=planner, seed=11)
    assert a.status is b.status and a.n_ticks == b.n_ticks
    assert np.array_equal(a.positions, b.positions)
    assert np.array_equal(a.times, b.times)
    assert np.array_equal(a.obstacle_positions, b.obstacle_positions)
    assert np.array_equal(a.sensed, b.sensed)
    c = simulate(_walkers(), planner=planner, seed=12)
    n = min(a.n_ticks, c.n_ticks) + 1
    assert not np.array_equal(a.obstacle_positions[:n, :2], c.obstacle_positions[:n, :2])


# ----------------------------------------------------------------------------- the record
def test_episode_record_is_consistent_and_json_ready():
    ep = simulate(_walkers(), planner="fusion", seed=1)
    t = ep.n_ticks
    k = 4
    assert ep.times.shape == (t + 1,) and ep.positions.shape == (t + 1, 2)
    assert ep.velocities.shape == (t, 2) and ep.plan_times_s.shape == (t,)
    assert ep.obstacle_positions.shape == (t + 1, k, 2) and ep.sensed.shape == (t + 1, k)
    assert np.allclose(ep.times, np.arange(t + 1) * 0.1)
    assert np.allclose(np.diff(ep.positions, axis=0), ep.velocities * 0.1)
    assert ep.path_length_m == pytest.approx(np.hypot(*np.diff(ep.positions, axis=0).T).sum())
    assert ep.positions[0].tolist() == [1.0, 1.0]
    assert ep.global_path is not None and ep.global_path[0].tolist() == [1.0, 1.0]
    # the global path is the waypoints of A* on the robot's c-space (global_astar.route)
    sc = ep.scenario
    assert np.array_equal(ep.global_path, route(sc.grid, sc.start, sc.goal, sc.robot.radius_m))
    assert ep.path_updates[0][0] == 0 and ep.path_updates[0][1] is ep.global_path
    if ep.reached:
        assert ep.time_to_goal_s == pytest.approx(ep.times[-1])
    # the sensing mask matches the sensing radius at every tick
    d = np.linalg.norm(ep.obstacle_positions - ep.positions[:, None, :], axis=-1) \
        - ep.obstacle_radii
    assert np.array_equal(ep.sensed, d <= 3.0)
    assert ep.min_distance_m == min(ep.min_obstacle_distance_m, ep.min_static_clearance_m)
    d = json.loads(json.dumps(ep.to_dict()))
    assert d["status"] == ep.status.name and len(d["positions"]) == t + 1
    assert d["mean_plan_time_s"] == pytest.approx(ep.mean_plan_time_s)
    assert "positions" not in ep.to_dict(trajectories=False)


def test_min_distance_matches_an_independent_computation():
    for sc in generate_scenarios(4, moving=4, speed_range=(0.4, 0.8), seed=9):
        ep = simulate(sc, planner="fusion")
        disc, static = _independent_min_gaps(ep)
        assert ep.min_obstacle_distance_m <= disc + 1e-12
        assert ep.min_obstacle_distance_m == pytest.approx(disc, abs=5e-3)
        assert ep.min_static_clearance_m == pytest.approx(min(static, 2.0), abs=5e-3)
        assert (ep.status is Status.COLLISION) == (min(disc, static) < -1e-9)


# ----------------------------------------------------------------------------- statuses
def test_no_path_for_path_planners_and_a_stall_for_apf():
    rows = ["....#....", "....#....", "....#...."]
    doc = {"map": {"rows": rows}, "start": [0.5, 1.5], "goal": [8.5, 1.5], "time_limit": 20}
    for planner in ["fusion", "astar", "astar-replan", "ref6", "ref7"]:
        ep = simulate(doc, planner=planner)
        assert ep.status is Status.NO_PATH and ep.n_ticks == 0
    ep = simulate(doc, planner="apf")
    assert ep.status is Status.LOCAL_MINIMUM
    assert ep.times[-1] >= 10.0                       # the default stall_time
    ep = simulate({**doc, "stall_time": 0}, planner="apf")
    assert ep.status is Status.TIMEOUT and ep.n_ticks == 200


U_TRAP = ["...........",
          "....###....",
          "......#....",
          "......#....",
          "......#....",
          "....###....",
          "..........."]


def test_apf_in_a_u_trap_is_a_local_minimum_and_fusion_is_not():
    doc = {"map": {"rows": U_TRAP}, "start": [1.5, 3.5], "goal": [9.5, 3.5]}
    assert simulate(doc, planner="apf").status is Status.LOCAL_MINIMUM
    ep = simulate(doc, planner="fusion")
    assert ep.status is Status.SUCCESS, ep.message
    assert _independent_min_gaps(ep)[1] >= 0.0
    # it is the escape that gets it out: it escaped (driving back along its own trail, every
    # move within the speed limit) and without the escape Algorithm 2 stalls in the trap
    ctrl, positions = _drive(doc, "fusion")
    assert np.array_equal(positions, ep.positions) and ctrl.escapes >= 1
    assert np.hypot(*np.diff(positions, axis=0).T).max() <= 1.0 * 0.1 + 1e-9
    paper = simulate(doc, planner={"name": "fusion", "params": {"escape": False}})
    assert paper.status is Status.LOCAL_MINIMUM


@pytest.mark.parametrize("turn", ["mirrored", "rot90", "rot270"])
def test_fusion_escapes_the_u_trap_whichever_way_it_faces(turn):
    # the escape drives back along the robot's trail, whatever the direction of travel
    occ = np.array([[c == "#" for c in row] for row in U_TRAP])
    mark = np.zeros(occ.shape, dtype=int)
    mark[3, 1], mark[3, 9] = 1, 2                       # start and goal cells (row from the top)
    f = {"mirrored": np.fliplr, "rot90": np.rot90, "rot270": lambda a: np.rot90(a, 3)}[turn]
    occ, mark = f(occ), f(mark)
    h = occ.shape[0]
    (rs, cs), (rg, cg) = np.argwhere(mark == 1)[0], np.argwhere(mark == 2)[0]
    doc = {"map": {"rows": ["".join("#" if v else "." for v in row) for row in occ]},
           "start": [cs + 0.5, h - 0.5 - rs], "goal": [cg + 0.5, h - 0.5 - rg]}
    ep = simulate(doc, planner="fusion")
    assert ep.status is Status.SUCCESS, ep.message
    ctrl, _ = _drive(doc, "fusion")
    assert ctrl.escapes >= 1
    assert simulate(doc, planner={"name": "fusion", "params": {"escape": False}}).status \
        is Status.LOCAL_MINIMUM


# ----------------------------------------------------------------------------- astar-replan
def test_astar_replan_replans_at_its_rate_and_goes_around_a_standing_disc():
    doc = head_on(obstacles=[{"position": [7.5, 2.5], "velocity": [0, 0], "radius": 0.6}])
    # the blind follower walks into the standing disc unless the shield steers it round
    blind = dict(doc, robot={**doc["robot"], "shield": False})
    assert simulate(blind, planner="astar").status is Status.COLLISION
    ep = simulate(doc, planner="astar")
    assert ep.status is Status.SUCCESS and ep.shield_counts["nearest"] > 0
    params = ReplanParams(replan_period_s=0.5)
    ep = run_episode(load_scenario(doc), "astar-replan", params)
    assert ep.status is Status.SUCCESS
    assert ep.planner == "astar-replan" and ep.params == dataclasses.asdict(params)
    # the same controller driven by hand: the same walk, and a replan every 5 ticks
    ctrl, positions = _drive(doc, "astar-replan", {"replan_period_s": 0.5})
    assert np.array_equal(positions, ep.positions)
    assert ctrl.replans == math.ceil(ep.n_ticks / 5) and ctrl.failed_replans == 0
    assert len(ep.path_updates) > 1 and ep.path_updates[0][0] == 0
    assert all(tick % 5 == 0 for tick, _ in ep.path_updates[1:])
    disc, static = _independent_min_gaps(ep)
    assert disc > 0 and static >= 0


# ----------------------------------------------------------------------------- what planners see
@dataclasses.dataclass(frozen=True)
class _SpyParams:
    pass


class _Spy(Controller):
    name = "spy"
    made: list[_Spy] = []

    def __init__(self, problem, params, plan=None, *, dt=None, max_speed=None):
        super().__init__(problem, params, plan, dt=dt, max_speed=max_speed)
        self.seen = []
        _Spy.made.append(self)

    def act(self, obs):
        self.seen.append(obs)
        return np.array([0.5, 0.0])


def test_planners_get_the_static_context_and_current_observations_only():
    sc = load_scenario(_walkers())
    register(PlannerSpec("spy", _SpyParams, "records what it sees", controller=_Spy))
    _Spy.made.clear()
    ep = run_episode(sc, "spy", seed=3)
    assert ep.planner == "spy" and len(_Spy.made) == 1
    spy = _Spy.made[0]
    # before the first tick a controller knows the static problem, the tick and the speed
    # limit - never the moving discs
    assert set(inspect.signature(Controller.__init__).parameters) == \
        {"self", "problem", "params", "plan", "dt", "max_speed"}
    assert {f.name for f in dataclasses.fields(Problem)} == \
        {"grid", "start", "goal", "robot_radius_m", "budget", "start_cell", "goal_cell",
         "clearance_m", "robot"}
    pb = spy.problem
    assert pb.robot is sc.robot and pb.clearance_m == sc.robot.clearance_m
    assert pb.grid is sc.grid and pb.start == sc.start and pb.goal == sc.goal
    assert pb.robot_radius_m == sc.robot.radius_m
    assert (spy.dt, spy.max_speed, spy.online, spy.plan) == (sc.dt, sc.robot.max_speed_mps, True,
                                                             None)
    assert all(isinstance(o, Observation) for o in spy.seen)
    assert [o.tick for o in spy.seen] == list(range(ep.n_ticks))
    for o in spy.seen:
        k = o.tick
        assert np.array_equal(o.obstacles.ids, np.flatnonzero(ep.sensed[k]))
        assert np.array_equal(o.obstacles.positions, ep.obstacle_positions[k, o.obstacles.ids])
        if k:
            past = (ep.obstacle_positions[k] - ep.obstacle_positions[k - 1]) / sc.dt
            assert np.allclose(o.obstacles.velocities, past[o.obstacles.ids])


# ----------------------------------------------------------------------------- repulsion
def test_position_repulsion_is_eq6_on_the_gap():
    pos = np.array([[3.0, 0.0]])
    fx, fy = disc_repulsion(0.0, 0.0, 0.0, 0.0, 0.2, pos, np.zeros((1, 2)), np.array([0.3]),
                            5.0, 2.0, 10.0, False, 1.0, 0.0, 1.0, 0.0)
    gap = 3.0 - 0.5
    assert (fx, fy) == (0.0, 0.0)                     # 2.5 m > rho0 = 2 m
    pos = np.array([[1.5, 0.0]])
    fx, fy = disc_repulsion(0.0, 0.0, 0.0, 0.0, 0.2, pos, np.zeros((1, 2)), np.array([0.3]),
                            5.0, 2.0, 10.0, False, 1.0, 0.0, 1.0, 0.0)
    gap = 1.5 - 0.5
    expect = repulsive_force([0.0, 0.0], [gap, 0.0], k_rep=5.0, rho0_m=2.0)
    assert [fx, fy] == pytest.approx(expect.tolist())
    assert fx < 0


def test_velocity_aware_repulsion_depends_on_the_closing_speed():
    pos = np.array([[1.5, 0.0]])
    rad = np.array([0.3])

    def f(vx, vy, ovx=0.0):
        return disc_repulsion(0.0, 0.0, vx, vy, 0.2, pos, np.array([[ovx, 0.0]]), rad, 5.0,
                              2.0, 10.0, True, 1.0, 0.0, 1.0, 0.0)

    assert f(-0.5, 0.0) == (0.0, 0.0)                 # moving away: no repulsion
    assert f(0.0, 0.0, 0.3) == (0.0, 0.0)             # the disc moves away
    slow, fast = f(0.3, 0.0), f(0.6, 0.0)
    assert fast[0] < slow[0] < 0.0                    # faster approach, stronger push
    assert f(0.0, 0.0, -0.3)[0] == pytest.approx(slow[0])   # only relative velocity counts
    side = f(0.4, 0.3)
    assert side[1] > 0.0                              # the sideways part speeds up passing


def test_swerve_passes_a_head_on_disc_on_the_right_and_a_crossing_disc_behind():
    rad = np.array([0.3])
    # heading +x, disc dead ahead and still: tangential push to the right (-y)
    _, fy = disc_repulsion(0.0, 0.0, 1.0, 0.0, 0.2, np.array([[1.5, 0.0]]), np.zeros((1, 2)),
                           rad, 5.0, 2.0, 10.0, False, 1.0, 1.0, 1.0, 0.0)
    assert fy < 0.0
    # a disc ahead-left moving to the right (-y) across the route: pass behind it (+y)
    _, fy = disc_repulsion(0.0, 0.0, 1.0, 0.0, 0.2, np.array([[1.5, 0.3]]),
                           np.array([[0.0, -0.5]]), rad, 5.0, 2.0, 10.0, False, 1.0, 1.0, 1.0,
                           0.0)
    assert fy > 0.0
    # a disc behind the robot gets no tangential part
    fx0, fy0 = disc_repulsion(0.0, 0.0, 1.0, 0.0, 0.2, np.array([[-1.5, 0.1]]),
                              np.zeros((1, 2)), rad, 5.0, 2.0, 10.0, False, 1.0, 0.0, 1.0, 0.0)
    fx1, fy1 = disc_repulsion(0.0, 0.0, 1.0, 0.0, 0.2, np.array([[-1.5, 0.1]]),
                              np.zeros((1, 2)), rad, 5.0, 2.0, 10.0, False, 1.0, 1.0, 1.0, 0.0)
    assert (fx0, fy0) == (fx1, fy1)


# ----------------------------------------------------------------------------- c-space
@pytest.mark.parametrize("seed", range(4))
def test_cspace_cell_centre_paths_keep_the_disc_clear(seed):
    rng = np.random.default_rng(seed)
    res = [0.05, 0.1, 0.5, 1.0][seed]
    g = GridMap(rng.random((14, 14)) < 0.12, resolution=res, origin=(0.3, -1.1))
    for r in rng.uniform(0.01, 3.0, 5) * res:
        occ = g.cspace(r).occupied
        free = np.argwhere(~occ)
        for rr, cc in free[rng.choice(len(free), size=min(40, len(free)), replace=False)]:
            for dr, dc in [(0, 1), (1, 0), (1, 1), (1, -1)]:
                r2, c2 = rr + dr, cc + dc
                if not (0 <= r2 < 14 and 0 <= c2 < 14) or occ[r2, c2]:
                    continue
                if dr and dc and (occ[rr + dr, cc] or occ[rr, cc + dc]):
                    continue   # no corner cutting
                a = g.cell_to_world([rr, cc])[0]
                b = g.cell_to_world([r2, c2])[0]
                x0, y0, x1, y1 = g.bounds
                assert min(a[0] - x0, x1 - a[0], a[1] - y0, y1 - a[1]) >= r
                for br, bc in np.argwhere(g.occupied):
                    bx, by = g.origin[0] + bc * res, g.origin[1] + br * res
                    if abs(bx - a[0]) > r + 2 * res or abs(by - a[1]) > r + 2 * res:
                        continue
                    assert _seg_box(a, b, (bx, by, bx + res, by + res)) >= r - 1e-9
