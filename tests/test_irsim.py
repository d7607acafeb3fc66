"""The IR-SIM adapter, episode runner, study and command against IR-SIM itself (issue 18)."""

from __future__ import annotations

import json
import math
import os
import sqlite3
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("irsim", reason="IR-SIM is an optional extra: pip install 'pathfuse[irsim]'")

from pathfuse.integrations.irsim import (  # noqa: E402
    IrsimController,
    example_worlds_dir,
    make_env,
    rasterise_static,
    read_scene,
)
from pathfuse.integrations.irsim_run import (  # noqa: E402
    RVO_BASELINE,
    read_world_spec,
    run_irsim_episode,
)
from pathfuse.result import ConfigError  # noqa: E402
from pathfuse.world.social import social_metrics  # noqa: E402

EXAMPLES = Path(example_worlds_dir())

ROBOT_DIFF = """
robot:
  - kinematics: {name: diff}
    shape: {name: circle, radius: 0.25}
    state: [0.7, 2.0, 0.0]
    goal: [5.3, 2.0, 0.0]
    vel_max: [1.0, 2.0]
    vel_min: [0.0, -2.0]
    acce: [2.0, 4.0]
    goal_threshold: 0.3
"""

ROBOT_OMNI = """
robot:
  - kinematics: {name: omni}
    shape: {name: circle, radius: 0.25}
    state: [0.7, 2.0, 1.5708]
    goal: [5.3, 2.0, 0.0]
    vel_max: [1.0, 1.0]
    vel_min: [-1.0, -1.0]
    goal_threshold: 0.3
"""

BOX = """
world: {height: 4, width: 6, step_time: 0.1, collision_mode: stop}
obstacle:
  - shape: {name: rectangle, length: 0.8, width: 1.0}
    state: [3.0, 2.0, 0.0]
custom:
  pathfuse: {time_limit_s: 20}
"""


def _world(tmp_path: Path, text: str, name: str = "w.yaml") -> Path:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def _drive(env, action_of, steps: int = 200) -> str:
    r = env.robot
    for _ in range(steps):
        env.step(action_of(env))
        if r.collision:
            return "collision"
        if r.arrive:
            return "arrived"
    return "timeout"


# --------------------------------------------------------------------------- the adapter
@pytest.mark.parametrize("robot", [ROBOT_DIFF, ROBOT_OMNI], ids=["diff", "omni"])
def test_irsim_reports_a_collision_for_a_bad_action_and_none_for_the_planners(tmp_path, robot):
    world = _world(tmp_path, BOX + robot)
    env = make_env(world)
    straight = np.array([[1.0], [0.0]]) if "diff" in robot else np.array([[0.0], [-1.0]])
    assert _drive(env, lambda e: straight) == "collision"  # into the box, says IR-SIM
    env = make_env(world)
    ctrl = IrsimController(env, planner="astar")
    assert _drive(env, ctrl.act) == "arrived"
    assert not env.robot.collision


def test_action_shapes_and_frames(tmp_path):
    env = make_env(_world(tmp_path, BOX + ROBOT_DIFF))
    ctrl = IrsimController(env, planner="fusion")
    a = ctrl.act(env)
    assert a.shape == (2, 1) and ctrl.scene.kinematics == "diff"
    assert 0.0 <= a[0, 0] <= 1.0  # (v, omega) within the robot's limits
    env = make_env(_world(tmp_path, BOX + ROBOT_OMNI, "o.yaml"))
    ctrl = IrsimController(env, planner="astar")
    assert ctrl.scene.robot.kind == "holonomic"
    x0 = float(env.robot.state[0, 0])
    a = ctrl.act(env)
    assert a.shape == (2, 1)
    # the robot faces +y; going +x (towards the goal, around the box) is a lateral command
    # to its right in IR-SIM's body frame
    assert a[1, 0] < 0.0
    for _ in range(5):
        env.step(ctrl.act(env))
    assert float(env.robot.state[0, 0]) > x0 + 0.1


def test_robot_model_follows_irsim_limits(tmp_path):
    env = make_env(_world(tmp_path, BOX + ROBOT_DIFF))
    sc = read_scene(env, sensing_radius_m=4.0, robot_overrides={"clearance_m": 0.1})
    rb = sc.robot
    assert (rb.kind, rb.max_speed_mps, rb.max_accel_mps2) == ("diff-drive", 1.0, 2.0)
    # planned with IR-SIM's radius grown by the Euler step's largest gap over a stop
    assert rb.radius_m == 0.25 + sc.euler_margin_m and 0.02 < sc.euler_margin_m < 0.025
    assert (rb.max_yaw_rate_radps, rb.max_yaw_accel_radps2, rb.min_speed_mps) == (2.0, 4.0, 0.0)
    assert (rb.sensing_radius_m, rb.clearance_m) == (4.0, 0.1)
    assert sc.goal == (5.3, 2.0) and sc.goal_tolerance_m == 0.3 and sc.dt_s == 0.1
    with pytest.raises(ConfigError, match="robot_overrides.wings"):
        read_scene(env, robot_overrides={"wings": 2})
    with pytest.raises(ConfigError, match="no robot 3"):
        IrsimController(env, robot=3)
    with pytest.raises(ConfigError, match="unknown planner"):
        IrsimController(env, planner="teleport")


SHAPES = """
world: {height: 6, width: 8, step_time: 0.1}
obstacle:
  - shape: {name: circle, radius: 0.55}
    state: [1.6, 1.7, 0.0]
  - shape: {name: rectangle, length: 1.3, width: 0.7}
    state: [4.9, 1.5, 0.6]
  - shape: {name: polygon, vertices: [[3.0, 3.6], [5.2, 3.6], [5.2, 5.4], [4.6, 5.4], [4.6, 4.2],
                                      [3.0, 4.2]]}
    state: [0.0, 0.0, 0.0]
"""


def test_static_shapes_match_irsims_geometry_cell_by_cell(tmp_path):
    shapely = pytest.importorskip("shapely")
    env = make_env(_world(tmp_path, SHAPES + ROBOT_DIFF.replace("[5.3, 2.0", "[7.3, 0.4")
                          .replace("[0.7, 2.0", "[7.3, 5.5")))
    res = 0.07  # not a divisor of the shapes' sizes: cells straddle every edge
    g = rasterise_static(env, res, exclude=(env.robot.id,))
    assert g.shape == (math.ceil(6 / res - 1e-9), math.ceil(8 / res - 1e-9))
    geoms = [o.geometry for o in env.objects if o.static]
    assert len(geoms) == 3
    # an independent check: the area IR-SIM's own geometry shares with each cell square
    h, w = g.shape
    xs, ys = np.meshgrid(np.arange(w) * res, np.arange(h) * res)
    boxes = shapely.box(xs, ys, xs + res, ys + res)
    area = np.zeros((h, w))
    for geom in geoms:
        area = np.maximum(area, shapely.area(shapely.intersection(boxes, geom)))
    assert np.array_equal(g.occupied, area > 1e-10)
    assert g.occupied.sum() > 300


def test_grid_map_matches_irsims_own_collision_check(tmp_path):
    from irsim.world.map.obstacle_map import grid_collision_geometry
    from PIL import Image
    from shapely.geometry import Point

    img = np.full((40, 60), 255, dtype=np.uint8)  # 60 x 40 pixels over 6 m x 4 m: 0.1 m
    img[5:12, 10:25] = 0
    img[20:38, 40:44] = 0
    img[30, 5] = 0
    Image.fromarray(img).save(tmp_path / "map.png")
    text = (f"world: {{height: 4, width: 6, step_time: 0.1, "
            f"obstacle_map: {json.dumps(str(tmp_path / 'map.png'))}}}\n" + ROBOT_DIFF)
    env = make_env(_world(tmp_path, text.replace("[0.7, 2.0", "[0.3, 0.3")
                          .replace("[5.3, 2.0", "[5.7, 0.3")))
    wd = env._world
    reso = (float(wd.reso[0, 0]), float(wd.reso[1, 0]))
    mask = wd.grid_map > 50
    assert mask.sum() == 7 * 15 + 18 * 4 + 1
    same = rasterise_static(env, 0.1, exclude=(env.robot.id,))
    assert np.array_equal(same.occupied, mask.T)  # aligned cells: the same cells
    fine = rasterise_static(env, 0.05, exclude=(env.robot.id,))
    assert fine.occupied.sum() == 4 * mask.sum()
    # IR-SIM's own check: a point at the centre of each fine cell collides iff it is occupied
    for r, c in [(r, c) for r in range(0, 80, 3) for c in range(0, 120, 3)]:
        pt = Point((c + 0.5) * 0.05, (r + 0.5) * 0.05)
        hit = grid_collision_geometry(wd.grid_map, reso, pt, wd.offset)
        assert hit == bool(fine.occupied[r, c]), (r, c)


# --------------------------------------------------------------------------- episodes
def test_same_seed_same_episode_other_seed_other_people():
    world = EXAMPLES / "crossing_stream.yaml"
    a = run_irsim_episode(world, "astar", seed=3, time_limit_s=2.0)
    b = run_irsim_episode(world, "astar", seed=3, time_limit_s=2.0)
    c = run_irsim_episode(world, "astar", seed=4, time_limit_s=2.0)
    assert np.array_equal(a.positions, b.positions)
    assert np.array_equal(a.people_positions, b.people_positions)
    assert a.metrics()["min_gap_m"] == b.metrics()["min_gap_m"]
    assert not np.allclose(a.people_positions[0], c.people_positions[0])
    assert a.status.name == "TIMEOUT" and a.n_ticks == 20


def test_rvo_baseline_moves_the_robot_itself():
    ep = run_irsim_episode(EXAMPLES / "rvo_crowd.yaml", RVO_BASELINE, seed=0, time_limit_s=3.0)
    assert ep.planner == RVO_BASELINE and ep.act_times_s.size == 0
    assert ep.path_length_m > 1.0
    with pytest.raises(ConfigError, match="takes no parameters"):
        run_irsim_episode(EXAMPLES / "rvo_crowd.yaml", RVO_BASELINE, params={"k": 1})


def test_shipped_worlds_read(tmp_path):
    names = sorted(p.stem for p in EXAMPLES.glob("*.yaml"))
    assert names == ["corridor_head_on", "crossing_stream", "doorway", "overtake_slow_walker",
                     "rvo_crowd", "sfm_flows"]
    for n in names:
        spec = read_world_spec(EXAMPLES / f"{n}.yaml")
        assert spec.position_m > 0 and spec.speed_frac > 0 and spec.time_limit_s >= 40
        env = make_env(EXAMPLES / f"{n}.yaml")
        sc = read_scene(env)
        assert (sc.robot.kind, sc.robot.radius_m - sc.euler_margin_m, sc.robot.max_speed_mps) \
            == ("diff-drive", 0.25, 1.0)
        assert sc.grid.is_free(np.array([sc.start, sc.goal])).all()


def test_heldout_worlds_read():
    """The six held-out worlds (examples/irsim-heldout): one of each kind, the robot of the
    shipped worlds, start and goal free on the rasterised map."""
    held = EXAMPLES.parent / "irsim-heldout"
    names = sorted(p.stem for p in held.glob("*.yaml"))
    assert names == ["crossing_both_ways", "narrow_doorway", "overtake_two_walkers",
                     "rvo_two_lines", "sfm_wide_flows", "vertical_head_on"]
    kinds = set()
    for n in names:
        spec = read_world_spec(held / f"{n}.yaml")
        kinds.add(spec.kind)
        assert spec.position_m > 0 and spec.speed_frac > 0 and spec.time_limit_s >= 60
        sc = read_scene(make_env(held / f"{n}.yaml"))
        assert (sc.robot.kind, sc.robot.radius_m - sc.euler_margin_m, sc.robot.max_speed_mps) \
            == ("diff-drive", 0.25, 1.0)
        assert sc.grid.is_free(np.array([sc.start, sc.goal])).all()
    assert len(kinds) == 6


def test_orca_walkers_need_pyrvo(tmp_path):
    """IR-SIM leaves ORCA walkers standing when pyrvo is missing (it only logs an error):
    pathfuse refuses such a world, naming the key, rather than run another world."""
    import importlib.util

    text = (EXAMPLES / "rvo_crowd.yaml").read_text().replace(
        "behavior: {name: rvo, vxmax: 1.0, vymax: 1.0, acce: 1.0, factor: 1.0, mode: rvo}",
        "group_behavior: {name: orca}")
    assert "group_behavior: {name: orca}" in text
    w = tmp_path / "orca_crowd.yaml"
    w.write_text(text)
    if importlib.util.find_spec("pyrvo") is None:
        with pytest.raises(ConfigError, match=r"orca_crowd\.yaml: obstacle\[0\]\."
                                              r"group_behavior: .*pip install pyrvo"):
            read_world_spec(w)
        with pytest.raises(ConfigError, match=r"group_behavior 'orca' of a group of 8 .*pyrvo"):
            make_env(w)
    else:  # with pyrvo the walkers move
        read_world_spec(w)
        env = make_env(w)
        before = np.array([o.state[:2, 0] for o in env.obstacle_list[:8]])
        for _ in range(10):
            env.step(np.zeros((2, 1)))
        after = np.array([o.state[:2, 0] for o in env.obstacle_list[:8]])
        assert np.hypot(*(after - before).T).min() > 0.1  # every walker moved


def test_world_spec_errors_name_the_file_and_key(tmp_path):
    bad = _world(tmp_path, BOX.replace("time_limit_s: 20", "time_limit_s: -1") + ROBOT_DIFF)
    with pytest.raises(ConfigError, match=r"w\.yaml: custom\.pathfuse\.time_limit_s"):
        read_world_spec(bad)
    bad = _world(tmp_path, BOX.replace("time_limit_s: 20", "perturb: {jitter: 1}") + ROBOT_DIFF)
    with pytest.raises(ConfigError, match=r"perturb\.jitter: unknown key"):
        read_world_spec(bad)
    with pytest.raises(ConfigError, match="robot: missing"):
        read_world_spec(_world(tmp_path, BOX))
    with pytest.raises(ConfigError, match="no such IR-SIM world file"):
        read_world_spec(tmp_path / "nope.yaml")


# --------------------------------------------------------------------------- social metrics
def test_social_metrics_fault_and_intrusion():
    dt = 0.1
    robot = np.array([[0.0, 0.0], [0.1, 0.0], [0.2, 0.0], [0.2, 0.0], [0.2, 0.0]])
    # person 0 reached by the moving robot at tick 2; person 1 walks into it at tick 4
    p0 = np.array([[0.8, 0.0], [0.8, 0.0], [0.65, 0.0], [0.65, 0.0], [0.65, 0.0]])
    p1 = np.array([[0.2, 2.0], [0.2, 1.5], [0.2, 1.0], [0.2, 0.8], [0.2, 0.4]])
    m = social_metrics(robot, np.stack([p0, p1], axis=1), np.array([0.2, 0.2]), 0.25, dt)
    assert (m.contacts, m.at_fault_collisions) == (2, 1)
    assert m.min_gap_m == pytest.approx(-0.05)
    assert m.time_within_m_s == pytest.approx(4 * dt)
    assert m.path_irregularity_rad_per_m == 0.0
    none = social_metrics(robot, np.zeros((5, 0, 2)), np.zeros(0), 0.25, dt)
    assert none.min_gap_m == math.inf and none.contacts == 0
    zigzag = np.array([[0, 0], [1, 0], [1, 1], [2, 1]], dtype=float)
    z = social_metrics(zigzag, np.zeros((4, 0, 2)), np.zeros(0), 0.25, dt)
    assert z.path_irregularity_rad_per_m == pytest.approx(math.pi / 3)
    with pytest.raises(ValueError, match="people_positions"):
        social_metrics(robot, np.zeros((4, 1, 2)), np.zeros(1), 0.25, dt)


def test_simulate_episode_carries_social_metrics():
    from pathfuse import simulate

    ep = simulate(os.fspath(Path(__file__).parents[1] / "examples" / "scenarios" /
                            "head_on.yaml"), planner="astar")
    d = ep.to_dict(trajectories=False)
    assert d["social_min_gap_m"] == pytest.approx(ep.min_obstacle_distance_m, abs=0.05)
    assert d["social_min_gap_m"] >= ep.min_obstacle_distance_m - 1e-9  # ticks vs exact sweeps
    assert simulate({"map": {"rows": ["....."]}, "start": [0.5, 0.5], "goal": [4.5, 0.5],
                     "robot": {"radius": 0.2}}).social is None


# --------------------------------------------------------------------------- study and CLI
def test_cli_irsim_runs_stores_and_resumes(tmp_path, capsys):
    from pathfuse.cli import main

    out = tmp_path / "out"
    args = ["irsim", str(EXAMPLES / "doorway.yaml"), "--planners", "astar,irsim-rvo",
            "--seeds", "2", "--time-limit", "2", "--workers", "1", "--out", str(out), "--quiet"]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "4 episodes (2 planners x 1 world x 2 seeds)" in text
    assert "irsim-rvo" in text and (out / "irsim.md").is_file()
    rows = (out / "episodes.csv").read_text().splitlines()
    assert len(rows) == 1 + 4
    with sqlite3.connect(out / "study.db") as con:
        n = con.execute("SELECT COUNT(*) FROM runs").fetchone()[0]
    assert main(args) == 0  # resumed: nothing runs again
    with sqlite3.connect(out / "study.db") as con:
        assert con.execute("SELECT COUNT(*) FROM runs").fetchone()[0] == n == 4


@pytest.mark.parametrize("argv, message", [
    (["irsim", "no/such/world.yaml"], "no such IR-SIM world file or folder"),
    (["irsim", "{ex}/doorway.yaml", "--planners", "fusion,warp"], "unknown planner 'warp'"),
    (["irsim", "{ex}/doorway.yaml", "--param", "irsim-rvo.k=1"], "takes no parameters"),
    (["irsim", "{ex}/doorway.yaml", "--gif", "--gif-seed", "9", "--seeds", "2"],
     "--gif-seed: seed 9"),
])
def test_cli_irsim_errors_are_one_line(argv, message, capsys, tmp_path):
    from pathfuse.cli import main

    argv = [a.replace("{ex}", str(EXAMPLES)) for a in argv] + ["--out", str(tmp_path / "o")]
    assert main(argv) != 0
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert "Traceback" not in err


def test_experiment_irsim_entries_key_by_contents_and_name_bad_keys(tmp_path):
    import shutil

    from pathfuse.bench.experiment import experiment_from_dict

    shutil.copy(EXAMPLES / "doorway.yaml", tmp_path / "door.yaml")
    doc = {"seeds": 2, "maps": [{"irsim": "door.yaml"}],
           "planners": [{"name": "fusion", "kinds": ["irsim"]},
                        {"name": RVO_BASELINE, "kinds": ["irsim"]}]}
    runs = experiment_from_dict(doc, tmp_path / "e.yaml").expand()
    assert [(r.kind, r.group, r.planner, r.seed) for r in runs] == [
        ("irsim", "door", "fusion", 0), ("irsim", "door", RVO_BASELINE, 0),
        ("irsim", "door", "fusion", 1), ("irsim", "door", RVO_BASELINE, 1)]
    (tmp_path / "door.yaml").write_text((EXAMPLES / "doorway.yaml").read_text()
                                        .replace("time_limit_s: 50", "time_limit_s: 45"))
    again = experiment_from_dict(doc, tmp_path / "e.yaml").expand()
    assert {r.key for r in runs}.isdisjoint(r.key for r in again)  # the file's contents
    for maps, planners, msg in [
        ([{"irsim": "nope.yaml"}], [{"name": "fusion"}], r"maps\[0\]\.irsim: no such"),
        ([{"irsim": {"world": "door.yaml", "resolution_m": 0}}], [{"name": "fusion"}],
         r"maps\[0\]\.irsim\.resolution_m"),
        ([{"irsim": "door.yaml", "start": [0, 0]}], [{"name": "fusion"}],
         r"maps\[0\]\.start: not used with irsim"),
        ([{"irsim": "door.yaml"}], [{"name": RVO_BASELINE, "params": {"k": 1}}],
         r"planners\[0\]\.params\.k"),
    ]:
        with pytest.raises(ConfigError, match=msg):
            experiment_from_dict({"maps": maps, "planners": planners}, tmp_path / "e.yaml")


# --------------------------------------------------------------------------- IR-SIM's Euler step
def test_euler_margin_bounds_irsims_step_against_the_arcs_over_every_stop():
    """From any command in the limits, the stop the shield relies on (speed and turn rate
    to zero at their acceleration limits), stepped by IR-SIM's own forward-Euler kinematics,
    never leaves pathfuse's exact arcs by more than euler_margin_m."""
    from irsim.lib.algorithm.kinematics import differential_kinematics

    from pathfuse.integrations.irsim import euler_margin_m
    from pathfuse.robot import RobotModel
    from pathfuse.sweep import unicycle_pose

    rng = np.random.default_rng(3)
    worst_ratio = 0.0
    for _ in range(200):
        vmax, wmax = rng.uniform(0.2, 2.0), rng.uniform(0.5, 3.0)
        a, alpha, dt = rng.uniform(0.5, 4.0), rng.uniform(1.0, 8.0), rng.choice([0.05, 0.1, 0.2])
        rb = RobotModel.diff_drive(radius_m=0.25, max_speed_mps=vmax, max_accel_mps2=a,
                                   max_yaw_rate_radps=wmax, max_yaw_accel_radps2=alpha)
        bound = euler_margin_m(rb, dt)
        v, w = rng.uniform(0, vmax), rng.uniform(-wmax, wmax)
        s = np.array([[0.0], [0.0], [rng.uniform(-3, 3)]])
        x, y, th = 0.0, 0.0, float(s[2, 0])
        dev = 0.0
        for _ in range(1000):
            s = differential_kinematics(s, np.array([[v], [w]]), dt)
            x, y, _th = unicycle_pose(x, y, th, v, w, dt)
            th = float(s[2, 0])  # the headings agree; IR-SIM wraps its own
            dev = max(dev, math.hypot(float(s[0, 0]) - x, float(s[1, 0]) - y))
            if v == 0.0 and w == 0.0:
                break
            v = max(0.0, v - a * dt)
            w = math.copysign(max(0.0, abs(w) - alpha * dt), w)
        assert dev <= bound + 1e-12
        worst_ratio = max(worst_ratio, dev / bound)
    assert worst_ratio > 0.5  # the bound is not loose by much on the worst draws


def test_dwa_in_irsim_does_not_drive_into_a_wall():
    """Regression: dwa grazed the corridor's wall and IR-SIM's Euler step took it 1 mm in
    (corridor_head_on, seed 3: a static collision, the robot moving)."""
    ep = run_irsim_episode(Path(example_worlds_dir()) / "corridor_head_on.yaml", "dwa", 3)
    assert ep.collision_with != "static" and ep.collision_at_fault is not True


def test_fusion_waits_outside_a_crossing_stream():
    """Regression: among a stream of people crossing its corridor the fusion drove into
    their lane and was walked into from behind (crossing_stream, seed 3); the dwell
    critic keeps it out of the lane (without the replanned path's personal space, MPPI's
    lane_escape and the walker escape, each of which alone also avoids it now)."""
    world = Path(example_worlds_dir()) / "crossing_stream.yaml"
    before = {"seed": 3, "social_replan": False, "lane_escape": False, "walker_escape": False}
    ep = run_irsim_episode(world, "fusion", 3, before)
    assert ep.status.name == "SUCCESS" and ep.social.min_gap_m > 0.3
    off = run_irsim_episode(world, "fusion", 3, {**before, "dwell_s": 0.0})
    assert off.status.name == "COLLISION" and off.collision_with == "person"


def test_fusion_replans_with_personal_space_around_a_head_on_pair():
    """social_replan (ours, as dwa's): after passing the first pair low the fusion stood in
    the second pair's lane, turned to flee ahead of them and was walked into
    (corridor_head_on, seed 6); with the replanned path keeping personal_m from the people
    it passes both pairs.  (The lanes of replan_lane_s, replan_new, MPPI's lane_escape and
    the walker escape avoid it too: all off here.)"""
    world = Path(example_worlds_dir()) / "corridor_head_on.yaml"
    before = {"seed": 6, "replan_lane_s": 0.0, "replan_new": False, "lane_escape": False,
              "walker_escape": False}
    ep = run_irsim_episode(world, "fusion", 6, before)
    assert ep.status.name == "SUCCESS" and ep.social.min_gap_m > 0.3
    off = run_irsim_episode(world, "fusion", 6, {**before, "social_replan": False})
    assert off.status.name == "COLLISION" and off.collision_with == "person"


def test_mppi_replans_with_personal_space_around_a_head_on_pair():
    """social_replan (ours, as dwa's and the fusion's): without it mppi is walked into by
    the head-on pair (corridor_head_on, seed 1); with its replanned path keeping personal_m
    from the people it reaches the goal (passing 0.04 m from them: no collision, though not
    the personal space).  MPPI's lane_escape avoids it too: off here."""
    world = Path(example_worlds_dir()) / "corridor_head_on.yaml"
    ep = run_irsim_episode(world, "mppi", 1, {"seed": 1, "lane_escape": False})
    assert ep.status.name == "SUCCESS"
    off = run_irsim_episode(world, "mppi", 1, {"seed": 1, "social_replan": False,
                                               "lane_escape": False})
    assert off.status.name == "COLLISION" and off.collision_with == "person"


def test_fusion_leaves_the_lane_of_a_head_on_pair_rather_than_fleeing():
    """replan_lane_s (ours): after passing the first pair low the fusion sensed the second
    pair 5 m away, in their lane; Algorithm 2's local path led on into it, the robot slowed,
    turned round and fled ahead of walkers faster than itself, and was walked into
    (corridor_head_on, seed 3).  With the replanned A* path keeping out of the walkers'
    lanes over the next 3 s, and leading while the local path walks into one, it crosses
    to the free side in time.  (The walker escape, on by default since 27 Nov, avoids it
    too: off here.)"""
    world = Path(example_worlds_dir()) / "corridor_head_on.yaml"
    ep = run_irsim_episode(world, "fusion", 3, {"seed": 3, "walker_escape": False})
    assert ep.status.name == "SUCCESS" and ep.social.min_gap_m > 0.3
    off = run_irsim_episode(world, "fusion", 3, {"seed": 3, "replan_lane_s": 0.0,
                                                 "walker_escape": False})
    assert off.status.name == "COLLISION" and off.collision_with == "person"


def test_mppi_escapes_a_head_on_pair_instead_of_standing_in_its_lane():
    """lane_escape (ours, mppi_escape): mppi slowed in front of a pair walking head-on down a
    4.5 m corridor (1.5 m free on either side) and stood in their lane for 2.5 s until they
    walked into it (the training world examples/irsim-train/west_three_lanes_wide, seed
    1: every sample around standing met them, so the weighted mean stayed there).  With the
    fan of escape sequences scored against the optimum it turns out of their lane in time."""
    world = Path(example_worlds_dir()).parent / "irsim-train" / "west_three_lanes_wide.yaml"
    ep = run_irsim_episode(world, "mppi", 1, {"seed": 1}, time_limit_s=7.0)
    assert ep.status.name != "COLLISION" and ep.social.min_gap_m > 0.0
    off = run_irsim_episode(world, "mppi", 1, {"seed": 1, "lane_escape": False},
                            time_limit_s=7.0)
    assert off.status.name == "COLLISION" and off.collision_with == "person"
    assert off.collision_at_fault is False  # walked into while standing
