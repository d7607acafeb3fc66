"""The paper's algorithms as printed (``pathfuse paper --variant paper``), on hand-made cases,
and the reproduction's variants, references and excess over the shortest path."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pathfuse import Budget, GridMap, Status, plan
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.metrics import collision_free, evaluate
from pathfuse.planners.controllers.fusion import FusionParams, force_at
from pathfuse.studies.paper import (
    PAPER_VARIANT,
    PaperConfig,
    run_paper,
    summary_rows,
    write_paper_outputs,
)
from pathfuse.studies.paper_tables import excess

AS_PRINTED = PAPER_VARIANT["fusion"]
WALL = GridMap.from_rows(["..........", ".....#....", ".........."])  # square [5, 6] x [1, 2]


def test_the_paper_variant_is_everything_as_printed():
    assert AS_PRINTED == {"ahead": "paper-x", "escape": False, "safe_step": False,
                          "stall_exit": False}
    for name in ("apf", "ref6", "ref7"):
        assert PAPER_VARIANT[name] == {"safe_step": False, "stall_exit": False}
    # pathfuse's defaults are the other way round (ours, named, switchable)
    p = FusionParams()
    assert (p.ahead, p.escape, p.safe_step, p.stall_exit) == ("progress", True, True, True)


def test_eq8_attracts_only_points_with_larger_x():
    g = GridMap(np.zeros((6, 8), dtype=bool))
    x, goal = np.array([3.0, 3.0]), np.array([3.0, 0.5])   # the goal straight below
    path = np.array([[3.0, 2.5], [3.4, 2.0], [2.6, 2.0], [3.0, 3.0], [3.0, 0.5]])
    k = 40.0
    f = force_at(g, x, goal, path, FusionParams(ahead="paper-x", r1_m=1.2), progress=0)
    # eq. 8: x_p - x > 0 keeps only (3.4, 2.0); eq. 9 adds the goal's pull (eq. 5)
    want = -k * (x - goal) - k * (x - path[1])
    np.testing.assert_allclose(f, want)


def test_full_steps_of_the_paper_on_an_open_map():
    # no obstacle within rho0: the force is the attraction, every move is the full step
    g = GridMap(np.zeros((10, 10), dtype=bool))
    r = plan(g, (0.5, 0.5), (8.5, 6.5), planner="apf", step_m=0.25, **PAPER_VARIANT["apf"])
    assert r.success
    u = np.array([8.0, 6.0]) / 10.0
    steps = np.diff(r.path[:-1], axis=0)
    np.testing.assert_allclose(steps, np.tile(0.25 * u, (len(steps), 1)), atol=1e-12)


@pytest.mark.parametrize("name", ["apf", "fusion"])
def test_a_step_into_an_obstacle_is_a_collision(name):
    # the wall square lies on the straight line to the goal; the repulsion of eq. 6 from
    # its centre (K_rep 5) cannot turn the goal's pull (K_att 40 times ~5 m) in time
    kw = PAPER_VARIANT[name]
    r = plan(WALL, (0.5, 1.5), (9.5, 1.5), planner=name, **kw)
    assert r.status is Status.COLLISION and not r
    assert "touches an obstacle" in r.message
    assert not evaluate(WALL, r)["collision_free"]
    # the step that collides is in the path, and only the last one touches the square
    assert collision_free(WALL, r.path[:-1]) and not collision_free(WALL, r.path[-2:])
    # pathfuse's safe step never collides on the same query
    ours = plan(WALL, (0.5, 1.5), (9.5, 1.5), planner=name)
    assert evaluate(WALL, ours)["collision_free"] and ours.status is not Status.COLLISION


def test_a_disc_robot_collides_when_it_comes_closer_than_its_radius():
    r = plan(WALL, (0.5, 1.5), (9.5, 1.5), planner="apf", robot_radius_m=0.3,
             **PAPER_VARIANT["apf"])
    assert r.status is Status.COLLISION
    assert not collision_free(WALL, r.path, robot_radius_m=0.3)
    assert collision_free(WALL, r.path[:-1], robot_radius_m=0.3)


def test_no_stall_exit_runs_to_the_move_cap():
    # towards -x eq. 8 attracts the points already passed: the robot stops short of the
    # goal; pathfuse's stall test ends that as LOCAL_MINIMUM, the paper's loop runs on
    g = GridMap(np.zeros((3, 12), dtype=bool))
    ours = plan(g, (10.5, 1.5), (0.5, 1.5), planner="fusion", ahead="paper-x", escape=False)
    assert ours.status is Status.LOCAL_MINIMUM
    r = plan(g, (10.5, 1.5), (0.5, 1.5), planner="fusion", budget=Budget(max_iterations=500),
             **AS_PRINTED)
    assert r.status is Status.MAX_ITERATIONS and r.iterations == 500
    assert math.dist(r.path[-1], (0.5, 1.5)) > 1.0
    # towards +x the same algorithm reaches the goal along the straight A* path
    r = plan(g, (0.5, 1.5), (10.5, 1.5), planner="fusion", **AS_PRINTED)
    assert r.success and r.length == pytest.approx(10.0)


def test_online_the_paper_step_drives_into_the_wall():
    from pathfuse import simulate

    # (a disc robot: the world's collision test is an overlap, which a point never has; the
    # algorithm alone: the safety shield, which stops it in time, off)
    sc = {"map": {"rows": ["..........", ".....#....", ".........."]},
          "start": [0.5, 1.5], "goal": [9.5, 1.5], "robot": {"radius": 0.2, "shield": False}}
    ep = simulate(sc, planner={"name": "apf", "params": PAPER_VARIANT["apf"]})
    assert ep.status is Status.COLLISION and ep.collision_with == "static"
    assert simulate(sc, planner="apf").status is not Status.COLLISION
    # with the shield the same commands never reach the wall
    shielded = dict(sc, robot={"radius": 0.2})
    ep = simulate(shielded, planner={"name": "apf", "params": PAPER_VARIANT["apf"]})
    assert ep.status is not Status.COLLISION and ep.shield_counts["nearest"] > 0


# ------------------------------------------------------------------ the reproduction
@pytest.fixture(scope="module")
def run():
    return run_paper(PaperConfig(n_seeds=8, first_seed=0, figure_seed=3))


def test_columns_of_both_variants(run):
    cfg = run.config
    assert cfg.table_columns("pathfuse") == ["astar", "apf", "ref6", "ref7", "fusion",
                                             "astar-smooth", "thetastar", "shortest"]
    assert cfg.table_columns("paper") == ["astar", "apf/paper", "ref6/paper", "ref7/paper",
                                          "fusion/paper", "astar-smooth", "thetastar",
                                          "shortest"]
    assert len(run.records) == 8 * 12
    # the paper variant's runs are what plan() gives with PAPER_VARIANT
    for r in run.by_planner("fusion/paper"):
        g = paper_map(r["seed"])
        p = plan(g, PAPER_START, PAPER_GOAL, planner="fusion", k_att=40.0, k_rep=5.0,
                 rho0_m=2.0, step_m=0.1, **AS_PRINTED)
        assert r["status"] == p.status.name
        assert r["length_m"] == pytest.approx(p.length)


def test_pathfuse_variant_unchanged_by_the_other_columns(run):
    alone = run_paper(PaperConfig(n_seeds=8, variants=("pathfuse",), references=()))
    for name in ("astar", "apf", "ref6", "ref7", "fusion"):
        a = [(r["seed"], r["status"], r["length_m"]) for r in alone.by_planner(name)]
        b = [(r["seed"], r["status"], r["length_m"]) for r in run.by_planner(name)]
        assert a == b, name


def test_excess_over_the_shortest_path(run):
    low = {r["seed"]: r["length_m"] for r in run.by_planner("shortest")}
    assert all(r["success"] for r in run.by_planner("shortest"))
    rows = {(r["variant"], r["planner"]): r for r in summary_rows(run)}
    for col in ("astar", "thetastar", "astar-smooth", "fusion"):
        want = [(r["length_m"] - low[r["seed"]]) / low[r["seed"]]
                for r in run.by_planner(col) if r["success"]]
        np.testing.assert_allclose(excess(run, col), want)
        assert rows[("pathfuse", col)]["excess_mean"] == pytest.approx(np.mean(want))
        assert min(want) >= -1e-9
    # the fusion of each variant is its own table's R_length reference
    assert rows[("paper", "astar")]["r_length_pairs"] == sum(
        r["success"] for r in run.by_planner("fusion/paper"))


def test_corner_cutting_reference():
    cut = run_paper(PaperConfig(n_seeds=8, variants=("pathfuse",), references=(),
                                corner_cutting=True))
    plain = run_paper(PaperConfig(n_seeds=8, variants=("pathfuse",), references=()))
    for a, b in zip(cut.by_planner("astar"), plain.by_planner("astar"), strict=True):
        assert a["length_m"] <= b["length_m"] + 1e-12
    assert cut.config.label("astar") == "A-star (corner cutting)"
    # the paper's Table I A* length is the corner-cutting length 9 sqrt(2) + 2
    assert any(abs(r["length_m"] - (9 * math.sqrt(2) + 2)) < 1e-9 for r in cut.by_planner("astar"))


def test_outputs_hold_both_variants(run, tmp_path):
    files = write_paper_outputs(run, tmp_path)
    md = files["tables_md"].read_text()
    assert "pathfuse variant: path length" in md and "paper variant: path length" in md
    assert "Excess over the shortest path mean" in md and "Theta*" in md
    assert "(as printed)" in md and "COLLISION" in md
