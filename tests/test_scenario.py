"""Scenario files: parsing, one-line errors naming the key, scene checks, round trips, generator."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pytest

from pathfuse import ConfigError, GridMap, MapError, MapFormatError, Status
from pathfuse.planners.registry import planner_names
from pathfuse.sweep import segment_static_distance
from pathfuse.world import (
    LinearObstacle,
    PatrolObstacle,
    RandomWalkObstacle,
    ScenarioError,
    load_scenario,
    save_scenario,
    simulate,
)
from pathfuse.world.generate import generate_scenarios

DATA = Path(__file__).parent / "data" / "scenarios"
EXAMPLES = Path(__file__).parent.parent / "examples" / "scenarios"

BASE = {
    "map": {"rows": ["..........", "..........", "...#......", ".........."]},
    "start": [0.5, 0.5],
    "goal": [9.5, 3.5],
    "robot": {"radius": 0.2, "max_speed": 1.0, "sensing_radius": 3.0},
    "dt": 0.1,
    "time_limit": 30,
    "obstacles": [
        {"position": [5.5, 1.5], "velocity": [0.0, 0.5], "radius": 0.3},
        {"waypoints": [[1.5, 3.5], [8.5, 3.5]], "speed": 0.6, "radius": 0.3, "loop": True},
        {"random_walk": {"position": [7.5, 0.5], "speed": 0.4, "seed": 1}, "radius": 0.3},
    ],
    "planner": {"name": "fusion", "params": {}},
}


def _with(path: str, value):
    """BASE with the key at ``path`` (dots and [i]) set to ``value`` (``...`` deletes it)."""
    doc = copy.deepcopy(BASE)
    keys = []
    for part in path.replace("]", "").split("."):
        for i, k in enumerate(part.split("[")):
            keys.append(int(k) if i else k)
    d = doc
    for k in keys[:-1]:
        d = d[k]
    if value is ...:
        del d[keys[-1]]
    else:
        d[keys[-1]] = value
    return doc


def test_base_and_files_load():
    sc = load_scenario(BASE)
    assert [type(o) for o in sc.obstacles] == [LinearObstacle, PatrolObstacle,
                                               RandomWalkObstacle]
    assert sc.n_steps == 300 and sc.robot.sensing_radius_m == 3.0
    m = load_scenario(DATA / "minimal.yaml")
    assert (m.dt, m.time_limit, m.goal_tolerance, m.robot.radius_m, m.planner.name) == \
        (0.1, 60.0, 0.25, 0.2, "fusion")
    assert m.name == "minimal" and m.obstacles == ()
    f = load_scenario(DATA / "full.yaml")
    assert (f.dt, f.seed, f.robot.max_speed_mps, f.planner.name) == (0.05, 9, 0.8, "astar-replan")
    assert f.planner.params == {"replan_period_s": 0.5, "margin_m": 0.1}
    assert f.obstacles[2].heading == 1.0 and f.obstacles[1].loop is False
    # the older name of the astar planner still loads, as the canonical name
    old = load_scenario(_with("planner", {"name": "astar-follow", "params": {"heuristic":
                                                                              "octile"}}))
    assert (old.planner.name, old.planner.params) == ("astar", {"heuristic": "octile"})
    assert old.to_dict()["planner"]["name"] == "astar"


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.yaml")), ids=lambda p: p.name)
def test_example_scenarios_load_and_run(path):
    sc = load_scenario(path)
    ep = simulate(sc)
    assert ep.n_ticks > 0 and isinstance(ep.status, Status)
    assert ep.planner == sc.planner.name


# (key path, bad value, text the message must contain); the message must start with the key
MALFORMED = [
    ("dt", "fast", "dt: must be a number > 0, got 'fast'"),
    ("dt", 0, "dt: must be a number > 0, got 0"),
    ("dt", True, "dt: must be a number > 0, got True"),
    ("time_limit", -5, "time_limit: must be a number > 0"),
    ("goal_tolerance", float("nan"), "goal_tolerance: must be a finite number"),
    ("stall_time", -1, "stall_time: must be a number >= 0"),
    ("stall_radius", "x", "stall_radius: must be a number > 0"),
    ("seed", 1.5, "seed: must be an integer >= 0, got 1.5"),
    ("seed", -3, "seed: must be an integer >= 0"),
    ("name", 7, "name: must be a string"),
    ("start", [1.0], "start: must be two numbers [x, y]"),
    ("start", "here", "start: must be two numbers [x, y]"),
    ("goal", [1.0, "y"], "goal[1]: must be a number"),
    ("robot", 3, "robot: must be a mapping"),
    ("robot.radius", -0.1, "robot.radius: must be a number >= 0"),
    ("robot.max_speed", 0, "robot.max_speed: must be a number > 0"),
    ("robot.sensing_radius", "far", "robot.sensing_radius: must be a number > 0"),
    ("robot.size", 1, "robot.size: unknown key (allowed: radius, max_speed, sensing_radius, "
                      "model, max_accel, max_yaw_rate, max_yaw_accel, min_speed, clearance, "
                      "inflation, heading, shield, recovery)"),
    ("robot.model", "tank", "robot.model: must be one of 'holonomic', 'diff-drive', got 'tank'"),
    ("robot.max_accel", 0, "robot.max_accel: must be a number > 0"),
    ("robot.max_yaw_rate", "fast", "robot.max_yaw_rate: must be a number > 0"),
    ("robot.min_speed", 0.5, "robot.min_speed: must be a number <= 0"),
    ("robot.min_speed", -0.5, "robot.min_speed: must be 0 for a holonomic robot (only a "
                             "diff-drive robot reverses), got -0.5"),
    ("robot.clearance", -0.1, "robot.clearance: must be a number >= 0"),
    ("obstacles", {"a": 1}, "obstacles: must be a list"),
    ("obstacles[0]", 5, "obstacles[0]: must be a mapping"),
    ("obstacles[0].velocity", [0.5], "obstacles[0].velocity: must be two numbers"),
    ("obstacles[0].radius", 0, "obstacles[0].radius: must be a number > 0, got 0"),
    ("obstacles[0].speed", 1.0, "obstacles[0].speed: unknown key (allowed: position, velocity"),
    ("obstacles[0].position", ..., "obstacles[0]: an obstacle needs 'position'"),
    ("obstacles[1].speed", "fast", "obstacles[1].speed: must be a number > 0, got 'fast'"),
    ("obstacles[1].speed", ..., "obstacles[1].speed: missing"),
    ("obstacles[1].loop", "yes", "obstacles[1].loop: must be true or false, got 'yes'"),
    ("obstacles[1].waypoints", [[1.5, 3.5]], "obstacles[1].waypoints: must be a list of at "
                                             "least two"),
    ("obstacles[1].waypoints[1]", [8.5], "obstacles[1].waypoints[1]: must be two numbers"),
    ("obstacles[1].velocity", [1, 0], "obstacles[1].velocity: unknown key"),
    ("obstacles[2].random_walk", 3, "obstacles[2].random_walk: must be a mapping"),
    ("obstacles[2].random_walk.speed", -1, "obstacles[2].random_walk.speed: must be a number"),
    ("obstacles[2].random_walk.seed", "a", "obstacles[2].random_walk.seed: must be an integer"),
    ("obstacles[2].random_walk.turn_std", -1, "obstacles[2].random_walk.turn_std: must be"),
    ("obstacles[2].random_walk.heading", "north", "obstacles[2].random_walk.heading: must be"),
    ("obstacles[2].random_walk.walk", 1, "obstacles[2].random_walk.walk: unknown key"),
    ("obstacles[2].random_walk.position", ..., "obstacles[2].random_walk.position: missing"),
    ("obstacles[2].velocity", [1, 0], "obstacles[2].velocity: unknown key"),
    ("planner", 5, "planner: must be a planner name or {name, params}"),
    ("planner.name", "dijkstra", "planner.name: unknown planner 'dijkstra'; choose one of: "),
    ("planner.name", ..., "planner.name: missing"),
    ("planner.params", [1], "planner.params: must be a mapping"),
    ("planner.params", {"k_att": -1}, "planner.params.k_att: must be a number > 0, got -1"),
    ("planner.params", {"kat": 1}, "planner.params.kat: unknown parameter (parameters: "
                                   "global_planner, k_att, k_rep, rho0_m"),
    ("planner.params", {"escape_ticks": 20}, "planner.params.escape_ticks: unknown parameter"),
    ("planner.params", {"robot_radius_m": 0.2}, "planner.params.robot_radius_m: unknown "
                                                "parameter"),
    ("planner.params", {"repulsion": "magic"}, "planner.params.repulsion: must be one of"),
    ("planner.verbose", True, "planner.verbose: unknown key"),
    ("speed", 1, "speed: unknown key (allowed: name, description, map"),
    ("map", 3, "map: must be a map spec"),
    ("map", {"rows": ["..", ".x"]}, "map: "),
    ("map", {"paper": {"sed": 3}}, "map: unknown key 'paper.sed'"),
    ("map", ..., "map: missing"),
    ("goal", ..., "goal: missing"),
]


@pytest.mark.parametrize("path,value,text", MALFORMED,
                         ids=[f"{p}={v!r}"[:40] for p, v, _ in MALFORMED])
def test_malformed_key_gives_one_line_naming_the_key(path, value, text):
    with pytest.raises((ConfigError, MapError)) as info:
        load_scenario(_with(path, value))
    msg = str(info.value)
    assert "\n" not in msg
    assert msg.startswith(text)


def test_an_unknown_planner_lists_every_planner():
    with pytest.raises(ScenarioError) as info:
        load_scenario(_with("planner.name", "dijkstra"))
    listed = str(info.value).split("choose one of: ", 1)[1].split(", ")
    # the built-in planners first, in a fixed order (plug-ins of other tests may follow)
    assert listed[:6] == ["astar", "astar-replan", "apf", "fusion", "ref6", "ref7"]
    assert listed == planner_names()


def test_file_errors_name_the_file_and_line():
    with pytest.raises(ScenarioError) as info:
        load_scenario(DATA / "bad_speed.yaml")
    assert str(info.value) == (f"{DATA / 'bad_speed.yaml'}: obstacles[1].speed: must be a "
                               f"number > 0, got 'fast'")
    with pytest.raises(MapFormatError, match=r"bad_syntax.yaml: line 3, column 5"):
        load_scenario(DATA / "bad_syntax.yaml")
    with pytest.raises(MapFormatError, match=r"duplicate_key.yaml: line 4.*duplicate key 'start'"):
        load_scenario(DATA / "duplicate_key.yaml")
    with pytest.raises(ScenarioError, match=r"list.yaml: a scenario must be a mapping"):
        load_scenario(DATA / "list.yaml")
    with pytest.raises(MapFormatError, match="scenario file not found"):
        load_scenario(DATA / "missing.yaml")


def test_yaml_exponent_numbers_are_numbers():
    sc = load_scenario(_with("dt", "1e-1"))
    assert sc.dt == 0.1


# ----------------------------------------------------------------------------- scene checks
@pytest.mark.parametrize("path,value,text", [
    ("start", [3.5, 1.5], "start: the robot (radius 0.2 m) at (3.5, 1.5) overlaps an occupied"),
    ("start", [0.1, 1.5], "start: the robot (radius 0.2 m) at (0.1, 1.5) overlaps"),  # edge
    ("goal", [12.0, 1.0], "goal: (12, 1) lies outside the map"),
    ("obstacles[0].position", [3.0, 1.5], "obstacles[0].position: the disc (radius 0.3 m)"),
    ("obstacles[0].position", [0.7, 0.7], "obstacles[0]: overlaps the robot at the start"),
    ("obstacles[1].waypoints", [[1.5, 1.5], [8.5, 1.5]],
     "obstacles[1].waypoints: the leg from waypoint 0 to waypoint 1 is blocked"),
    ("obstacles[2].random_walk.position", [3.5, 1.5], "obstacles[2].random_walk.position:"),
])
def test_scene_checks(path, value, text):
    with pytest.raises(ScenarioError) as info:
        load_scenario(_with(path, value))
    assert text in str(info.value)


def test_loop_closing_leg_is_checked():
    doc = _with("obstacles[1]", {"waypoints": [[2.5, 0.5], [4.5, 0.5], [4.5, 2.5]],
                                 "speed": 1, "radius": 0.3, "loop": True})
    with pytest.raises(ScenarioError, match="leg from waypoint 2 to waypoint 0"):
        load_scenario(doc)
    doc["obstacles"][1]["loop"] = False   # back and forth never takes the closing leg
    assert load_scenario(doc).obstacles[1].loop is False


# ----------------------------------------------------------------------------- round trips
def test_to_dict_and_save_round_trip(tmp_path):
    sc = load_scenario(BASE)
    d = sc.to_dict()
    json.dumps(d)
    again = load_scenario(d)
    assert again.to_dict() == d
    f = save_scenario(sc, tmp_path / "saved.yaml")
    back = load_scenario(f)
    assert back.to_dict() == {**d, "name": d["name"]}
    a, b = simulate(sc, seed=3), simulate(back, seed=3)
    assert np.array_equal(a.positions, b.positions)


def test_relative_map_files_resolve_against_the_scenario_file(tmp_path):
    (tmp_path / "maps").mkdir()
    (tmp_path / "maps" / "m.yaml").write_text('rows: ["....", "...."]\nresolution: 0.5\n')
    (tmp_path / "s.yaml").write_text(
        "map: {ros: maps/m.yaml}\nstart: [0.25, 0.25]\ngoal: [1.75, 0.75]\n")
    with pytest.raises((ConfigError, MapError), match="map: "):
        load_scenario(tmp_path / "s.yaml")   # not a ROS map: the error is prefixed with map:
    (tmp_path / "s.yaml").write_text(
        "map: maps/m.yaml\nstart: [0.25, 0.25]\ngoal: [1.75, 0.75]\n")
    sc = load_scenario(tmp_path / "s.yaml")
    assert sc.grid.shape == (2, 4) and sc.grid.resolution == 0.5


def test_a_gridmap_can_be_passed_directly():
    g = GridMap.from_rows(["....", "...."])
    sc = load_scenario({"map": g, "start": [0.5, 0.5], "goal": [3.5, 1.5]})
    assert sc.grid is g
    assert load_scenario(sc.to_dict()).grid.occupied.tolist() == g.occupied.tolist()


# ----------------------------------------------------------------------------- generator
def _gap_to_static(grid, p, r):
    return float(segment_static_distance(grid.occupied, grid.origin[0], grid.origin[1],
                                         grid.resolution, p[0], p[1], p[0], p[1], 10.0)) - r


@pytest.mark.parametrize("placement", ["route", "uniform"])
def test_generator_is_deterministic_and_places_discs_clear(placement):
    scs = generate_scenarios(12, moving=5, speed_range=(0.3, 0.7), seed=4, placement=placement)
    again = generate_scenarios(12, moving=5, speed_range=(0.3, 0.7), seed=4,
                               placement=placement)
    other = generate_scenarios(12, moving=5, speed_range=(0.3, 0.7), seed=5,
                               placement=placement)
    assert [s.to_dict() for s in scs] == [s.to_dict() for s in again]
    assert [s.to_dict() for s in scs] != [s.to_dict() for s in other]
    # scenario i does not depend on how many are drawn
    assert generate_scenarios(3, moving=5, speed_range=(0.3, 0.7), seed=4,
                              placement=placement)[2].to_dict() == scs[2].to_dict()
    kinds = set()
    for sc in scs:
        assert len(sc.obstacles) == 5
        r = sc.robot.radius_m
        for ob in sc.obstacles:
            kinds.add(ob.kind)
            speed = ob.speed if not isinstance(ob, LinearObstacle) else float(np.hypot(
                *ob.velocity))
            assert 0.3 <= speed <= 0.7
            p = np.asarray(ob.position)
            assert _gap_to_static(sc.grid, p, ob.radius) >= 0           # not on static cells
            assert np.hypot(*(p - np.asarray(sc.start))) - ob.radius - r >= 1.0  # nor the robot
    assert kinds == {"linear", "patrol", "random_walk"}


def test_generator_on_a_fixed_map_draws_connected_start_and_goal():
    rows = ["............", "....####....", "............", "....####....", "............"]
    scs = generate_scenarios(4, moving=2, seed=1, map={"rows": rows}, placement="uniform")
    for sc in scs:
        assert sc.grid.shape == (5, 12)
        assert sc.to_dict()["map"] == {"rows": rows}
        ep = simulate(sc, planner="astar")
        assert ep.status in (Status.SUCCESS, Status.COLLISION), ep.message


def test_generator_rejects_bad_arguments():
    with pytest.raises(ConfigError, match="speed_range"):
        generate_scenarios(1, speed_range=(0.5, 0.1))
    with pytest.raises(ConfigError, match="kinds"):
        generate_scenarios(1, kinds=("teleport",))
    with pytest.raises(ConfigError, match="placement"):
        generate_scenarios(1, placement="anywhere")
    with pytest.raises(ConfigError, match="moving"):
        generate_scenarios(1, moving=-1)
