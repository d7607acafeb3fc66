"""Seeded perturbation of a scenario's discs (``perturb:``; pathfuse.world.perturb)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from pathfuse.world import World, load_scenario, simulate
from pathfuse.world.obstacles import LinearObstacle, PatrolObstacle, RandomWalkObstacle
from pathfuse.world.scenario import ScenarioError

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "scenarios"

ROWS = ["............",
        "............",
        ".....##.....",
        "............",
        "............"]


def _doc(perturb=None, obstacles=None, seed=None):
    d = {"map": {"rows": ROWS}, "start": [0.5, 2.5], "goal": [11.5, 2.5],
         "robot": {"radius": 0.2}, "time_limit": 30,
         "obstacles": obstacles if obstacles is not None else [
             {"position": [9.0, 2.5], "velocity": [-0.5, 0.0], "radius": 0.3},
             {"waypoints": [[3.0, 0.5], [3.0, 4.5]], "speed": 0.4, "radius": 0.3},
             {"random_walk": {"position": [8.0, 4.0], "speed": 0.3, "seed": 2}, "radius": 0.3},
         ]}
    if perturb is not None:
        d["perturb"] = perturb
    if seed is not None:
        d["seed"] = seed
    return d


P = {"position_m": 0.4, "speed_frac": 0.25, "heading_deg": 20}


def test_no_seed_or_no_section_is_the_scenario_as_written():
    sc = load_scenario(_doc(P))
    assert sc.obstacles_for(None) == sc.obstacles
    plain = load_scenario(_doc())
    assert plain.obstacles_for(5) == plain.obstacles
    # and the world: the same trajectories as the unperturbed scenario without a seed
    a = World(sc)
    a.reset(None)
    b = World(plain)
    b.reset(None)
    np.testing.assert_array_equal(a.obstacle_positions, b.obstacle_positions)


def test_every_draw_stays_within_its_bounds_and_keeps_kind_and_radius():
    sc = load_scenario(_doc(P))
    for seed in range(60):
        for ob, new in zip(sc.obstacles, sc.obstacles_for(seed), strict=True):
            assert type(new) is type(ob) and new.radius == ob.radius
            if isinstance(ob, PatrolObstacle):
                assert isinstance(new, PatrolObstacle)
                for w0, w1 in zip(ob.waypoints, new.waypoints, strict=True):
                    assert math.dist(w0, w1) <= P["position_m"] + 1e-12
                ratio = new.speed / ob.speed
            else:
                assert math.dist(ob.position, new.position) <= P["position_m"] + 1e-12
                ratio = new.speed / ob.speed
            assert 1 - P["speed_frac"] - 1e-12 <= ratio <= 1 + P["speed_frac"] + 1e-12
            if isinstance(ob, LinearObstacle):
                turn = math.atan2(new.velocity[1], new.velocity[0]) - math.atan2(
                    ob.velocity[1], ob.velocity[0])
                turn = (turn + math.pi) % (2 * math.pi) - math.pi
                assert abs(math.degrees(turn)) <= P["heading_deg"] + 1e-9
            if isinstance(ob, RandomWalkObstacle):
                assert new.seed == ob.seed and new.turn_std == ob.turn_std


def test_draws_are_valid_scenes_by_the_scenarios_own_check():
    # a disc beside the block and the map's edge: many draws land in it, none is kept
    obstacles = [{"position": [4.55, 2.5], "velocity": [0.0, 0.5], "radius": 0.3},
                 {"position": [11.6, 0.4], "velocity": [-0.2, 0.0], "radius": 0.3}]
    sc = load_scenario(_doc({"position_m": 1.0}, obstacles))
    moved = 0
    for seed in range(40):
        obs = sc.obstacles_for(seed)
        sc.replace(obstacles=obs)  # raises ScenarioError on an invalid scene
        moved += obs != sc.obstacles
    assert moved >= 35


def test_same_seed_same_episode_different_seeds_different_episodes():
    sc = load_scenario(_doc(P))
    a = simulate(sc, planner="dwa", seed=3)
    b = simulate(sc, planner="dwa", seed=3)
    c = simulate(sc, planner="dwa", seed=4)
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.obstacle_positions, b.obstacle_positions)
    assert not np.array_equal(a.obstacle_positions[0], c.obstacle_positions[0])


def test_each_disc_has_its_own_stream():
    doc = _doc(P)
    sc = load_scenario(doc)
    doc2 = _doc(P, obstacles=doc["obstacles"] + [
        {"position": [6.0, 0.5], "velocity": [0.0, 0.3], "radius": 0.2}])
    sc2 = load_scenario(doc2)
    assert sc2.obstacles_for(9)[:3] == sc.obstacles_for(9)


def test_round_trip_and_errors_name_the_key():
    sc = load_scenario(_doc(P))
    back = load_scenario(sc.to_dict())
    assert back.perturb == sc.perturb and back.obstacles_for(2) == sc.obstacles_for(2)
    with pytest.raises(ScenarioError, match=r"^perturb.speed_frac: must be a number .*1.*got 1.5"):
        load_scenario(_doc({"speed_frac": 1.5}))
    with pytest.raises(ScenarioError, match=r"^perturb.position_m: must be a number"):
        load_scenario(_doc({"position_m": -1}))
    with pytest.raises(ScenarioError, match=r"perturb.*spin"):
        load_scenario(_doc({"spin": 1}))


@pytest.mark.parametrize("name", ["head_on", "crossing", "corridor_overtake"])
def test_shipped_examples_give_n_episodes_for_n_seeds(name):
    sc = load_scenario(EXAMPLES / f"{name}.yaml")
    assert sc.perturb is not None and sc.perturb.active
    draws = {sc.obstacles_for(s) for s in range(8)}
    assert len(draws) == 8
