"""Who is at fault in a collision, the shield's counts, and how the BARN and dynamic studies
report them (also from databases written before these values existed)."""

from __future__ import annotations

import csv
import json
import math
import sqlite3
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pathfuse.result import Status
from pathfuse.shield import CODE_NAMES
from pathfuse.world import World, load_scenario, simulate
from pathfuse.world import episode as episode_mod

ROOT = Path(__file__).resolve().parents[1]
BARN = ROOT / "tests" / "data" / "barn"
HEAD_ON = ROOT / "examples" / "scenarios" / "head_on.yaml"
SHIELD_KEYS = [f"shield_{c}" for c in CODE_NAMES]

HOLONOMIC = {"radius": 0.2, "max_speed": 1.0}
DIFF_DRIVE = {"model": "diff-drive", "radius": 0.2, "max_speed": 1.0, "heading": 0.0}
ROBOTS = [pytest.param(HOLONOMIC, id="holonomic"), pytest.param(DIFF_DRIVE, id="diff-drive")]


def _doc(robot, obstacles=(), rows=None, start=(2.0, 3.0)):
    return {"map": {"rows": rows or ["." * 12] * 6}, "start": list(start), "goal": [11.5, 3.0],
            "robot": dict(robot), "dt": 0.1, "obstacles": list(obstacles), "time_limit": 30}


def _run(world, action, ticks=300):
    world.reset()
    for _ in range(ticks):
        _, term, trunc, info = world.step(action)
        assert info["at_fault"] is None or info["event"] == "collision"
        if term or trunc:
            return info
    raise AssertionError("no end")


# ----------------------------------------------------------------------------- the world
@pytest.mark.parametrize("robot", ROBOTS)
def test_a_disc_walking_into_a_standing_robot_is_not_its_fault(robot):
    disc = {"position": [6.0, 3.0], "velocity": [-1.0, 0.0], "radius": 0.3}
    info = _run(World(load_scenario(_doc(robot, [disc]))), (0.0, 0.0))
    assert info["event"] == "collision" and info["collision"] == 0
    assert info["at_fault"] is False


def test_a_diff_drive_robot_turning_on_the_spot_is_standing():
    disc = {"position": [6.0, 3.0], "velocity": [-1.0, 0.0], "radius": 0.3}
    info = _run(World(load_scenario(_doc(DIFF_DRIVE, [disc]))), (0.0, 1.0))
    assert info["collision"] == 0 and info["at_fault"] is False


@pytest.mark.parametrize("robot", ROBOTS)
def test_a_robot_driving_into_a_wall_is_at_fault(robot):
    rows = ["......#....."] * 6  # a wall at x = 6..7
    info = _run(World(load_scenario(_doc(robot, rows=rows))), (1.0, 0.0))
    assert info["collision"] == "static" and info["at_fault"] is True


@pytest.mark.parametrize("robot", ROBOTS)
def test_a_robot_driving_into_a_disc_is_at_fault(robot):
    # the disc walks away at 0.2 m/s, the robot catches up with it from behind at 1 m/s
    disc = {"position": [5.0, 3.0], "velocity": [0.2, 0.0], "radius": 0.3}
    info = _run(World(load_scenario(_doc(robot, [disc]))), (1.0, 0.0))
    assert info["collision"] == 0 and info["at_fault"] is True


@pytest.mark.parametrize("robot", ROBOTS)
def test_a_robot_moving_when_a_disc_hits_it_is_at_fault(robot):
    """The definition is the robot's motion, not who ran into whom: a robot creeping
    forward while a fast disc overtakes it from behind is at fault (it was moving)."""
    disc = {"position": [0.6, 3.0], "velocity": [1.0, 0.0], "radius": 0.3}
    info = _run(World(load_scenario(_doc(robot, [disc]))), (0.1, 0.0))
    assert info["collision"] == 0 and info["at_fault"] is True


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.sampled_from([0.0, 0.3, -0.5, 1.0]),
                          st.sampled_from([0.0, 0.7, -1.0])), min_size=1, max_size=60),
       st.booleans())
def test_at_fault_follows_the_applied_command(actions, diff):
    disc = {"position": [4.0, 3.5], "velocity": [-0.6, -0.2], "radius": 0.3}
    w = World(load_scenario(_doc(DIFF_DRIVE if diff else HOLONOMIC, [disc],
                                 rows=["..........#."] * 6)))
    w.reset()
    for a in actions:
        _, term, trunc, info = w.step(a)
        cmd = w.command
        if info["event"] != "collision":
            assert info["at_fault"] is None
        elif info["collision"] == "static":
            assert info["at_fault"] is True
        else:
            moving = cmd[0] != 0 if diff else (cmd[0] != 0 or cmd[1] != 0)
            assert info["at_fault"] is bool(moving)
        if term or trunc:
            break


# ----------------------------------------------------------------------------- the episode
class _Standing:
    """A controller that never moves (and has no shield counts)."""

    global_path = None
    failure = None

    def command(self, obs):
        return np.zeros(2)


def test_episode_of_a_robot_standing_while_a_disc_walks_in(monkeypatch):
    monkeypatch.setattr(episode_mod, "start_online", lambda *a, **k: _Standing())
    disc = {"position": [6.0, 3.0], "velocity": [-1.0, 0.0], "radius": 0.3}
    ep = simulate(_doc(HOLONOMIC, [disc]), planner="astar")
    assert ep.status is Status.COLLISION and ep.collision_with == 0
    assert ep.collision_at_fault is False and "standing still" in ep.message
    assert ep.shield_counts == {}  # the controller has none
    d = json.loads(json.dumps(ep.to_dict(trajectories=False)))
    assert d["collision_at_fault"] is False and d["shield_counts"] == {}


@pytest.mark.parametrize("robot", ROBOTS)
def test_episode_fields_and_shield_counts(robot):
    ep = simulate(HEAD_ON, planner="astar", robot=dict(robot, radius=0.2, sensing_radius=3.0))
    d = ep.to_dict(trajectories=False)
    assert list(ep.shield_counts) == list(CODE_NAMES)
    assert sum(ep.shield_counts.values()) == ep.n_ticks  # one shield decision per tick
    assert d["shield_counts"] == ep.shield_counts
    assert ep.status is Status.COLLISION  # astar walks on blind towards the disc
    # the shield may have stopped it in time (the disc then walks into it: not its
    # fault) or not: the flag is whether the last applied command moved the robot
    last = ep.commands[-1]
    moving = last[0] != 0 if ep.robot.is_diff_drive else bool(np.any(last != 0))
    assert ep.collision_at_fault is bool(moving)
    assert ("standing still" in ep.message) is (not moving)
    assert d["collision_at_fault"] == ep.collision_at_fault
    ok = simulate(HEAD_ON, planner="fusion")
    assert ok.status is Status.SUCCESS and ok.collision_at_fault is None


def test_episode_row_carries_the_values_into_the_store():
    from pathfuse.bench.execute import episode_row

    ep = simulate(HEAD_ON, planner="astar")
    assert ep.status is Status.COLLISION and ep.collision_at_fault is not None
    m = json.loads(episode_row(ep)["metrics"])
    assert m["collision_at_fault"] is ep.collision_at_fault
    assert {k: m[k] for k in SHIELD_KEYS} == {f"shield_{k}": v
                                             for k, v in ep.shield_counts.items()}
    ok = json.loads(episode_row(simulate(HEAD_ON, planner="fusion"))["metrics"])
    assert ok["collision_at_fault"] is None and ok["shield_asked"] > 0


def test_stored_values_of_old_rows():
    from pathfuse.world.episode import stored_at_fault, stored_shield_counts

    assert stored_at_fault({}, "SUCCESS") is None
    assert stored_at_fault({"collision_with": 1}, "COLLISION") is None  # unknown
    assert stored_at_fault({"collision_with": "static"}, "COLLISION") is True  # by definition
    assert stored_at_fault({"collision_with": 1, "collision_at_fault": False},
                           "COLLISION") is False
    assert stored_shield_counts({}) == dict.fromkeys(SHIELD_KEYS)


# ----------------------------------------------------------------------------- BARN
def _strip_new_values(db: Path) -> None:
    """Make a study database look written before these values existed."""
    keys = ", ".join(f"'$.{k}'" for k in ["collision_at_fault", *SHIELD_KEYS])
    with sqlite3.connect(db) as conn:
        conn.execute(f"UPDATE pathfuse_runs SET metrics = json_remove(metrics, {keys})")
    conn.close()


def _csv(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_barn_reports_the_new_columns(tmp_path):
    from pathfuse.studies.barn import BarnConfig, run_barn
    from pathfuse.studies.barn_report import json_lines, summary_rows, write_barn_outputs

    cfg = BarnConfig(str(BARN), worlds="17", planners=("fusion", "astar"))
    db = tmp_path / "study.db"
    run = run_barn(cfg, workers=1, db_path=db, trajectories=False)
    files = write_barn_outputs(run, tmp_path / "out")
    md = files["report_md"].read_text()
    assert "robot at fault / hit standing" in md
    assert "min static clearance (m), successes: p5 / p50" in md
    for rec in run.records:
        assert rec["status"] == "success" and rec["collision_at_fault"] is None
        assert sum(rec[k] for k in SHIELD_KEYS) == rec["ticks"]
    summ = _csv(files["summary_csv"])
    for row, rec in zip(summ, run.records, strict=True):
        assert row["planner"] == rec["planner"]
        assert row["collision_at_fault"] == row["collision_standing"] == "0"
        # one success: every percentile is its clearance
        assert float(row["min_static_clearance_p5_m"]) == pytest.approx(
            rec["min_static_clearance_m"], rel=1e-12)
        assert float(row["min_static_clearance_p50_m"]) == pytest.approx(
            rec["min_static_clearance_m"], rel=1e-12)
        assert int(row["shield_commands"]) == rec["ticks"]
        for old in ("success", "collision_rate", "timeout_ci_high", "metric_mean",
                    "time_mean_s", "timeout_detail"):
            assert old in row
    eps = _csv(files["episodes_csv"])
    assert {"collision_at_fault", *SHIELD_KEYS, "min_static_clearance_m",
            "message"} <= set(eps[0])
    js = [json.loads(s) for s in json_lines(run.records).splitlines()]
    assert {"collision_at_fault", *SHIELD_KEYS} <= set(js[0])
    # the same database, as an older pathfuse wrote it: it still summarises, with n/a
    _strip_new_values(db)
    old = run_barn(cfg, workers=1, db_path=db, trajectories=False)
    assert all(r[k] is None for r in old.records for k in SHIELD_KEYS)
    rows = summary_rows(old.records, cfg.planners)
    assert all(r["shield_asked"] is None and math.isnan(r["shield_replaced_rate"])
               for r in rows)
    files = write_barn_outputs(old, tmp_path / "old")
    md = files["report_md"].read_text()
    fusion_line = next(s for s in md.splitlines() if s.startswith("| fusion |"))
    assert fusion_line.rstrip().endswith("| n/a |")
    assert _csv(files["summary_csv"])[0]["shield_asked"] == ""


def test_barn_summary_splits_collisions_and_shows_n_a():
    from pathfuse.studies.barn_report import summary_rows, text_table

    def rec(status, fault, clear=0.1):
        return {"planner": "p", "status": status, "time_s": 5.0, "metric": 0.0,
                "collision_at_fault": fault, "min_static_clearance_m": clear}

    recs = [rec("collision", True), rec("collision", True), rec("success", None, 0.2),
            rec("success", None, 0.4), rec("timeout", None)]
    (r,) = summary_rows(recs, ["p"])
    assert (r["collision_at_fault"], r["collision_standing"]) == (2, 0)
    assert r["collision_at_fault_rate"] == pytest.approx(0.4)
    assert r["min_static_clearance_n"] == 2
    assert r["min_static_clearance_p50_m"] == pytest.approx(0.3)
    assert r["min_static_clearance_p5_m"] == pytest.approx(0.21)
    assert "2 / 0" in text_table([r])
    # a collision stored without the value: the split is unknown, not guessed
    (u,) = summary_rows(recs + [rec("collision", None)], ["p"])
    assert u["collision_at_fault"] is None and u["collision_fault_unknown"] == 1
    assert math.isnan(u["collision_at_fault_rate"])
    line = text_table([u]).splitlines()[1]
    assert "n/a" in line
    # no success: the percentiles are n/a
    (f,) = summary_rows([rec("timeout", None)], ["p"])
    assert math.isnan(f["min_static_clearance_p5_m"])


# ----------------------------------------------------------------------------- dynamic
def test_dynamic_reports_the_new_columns_and_old_databases(tmp_path):
    from pathfuse.studies.dynamic import (
        DynamicConfig,
        run_dynamic,
        summary_rows,
        write_dynamic_outputs,
    )

    cfg = DynamicConfig(n_seeds=3, moving=(0, 6), planners=("astar", "fusion"), seed=3)
    db = tmp_path / "study.db"
    run = run_dynamic(cfg, db_path=db)
    coll = [r for r in run.records if r["status"] == "COLLISION"]
    assert coll, "the blind astar should walk into a disc"
    for r in run.records:
        assert (r["collision_at_fault"] is None) == (r["status"] != "COLLISION")
        assert all(isinstance(r[k], int) for k in SHIELD_KEYS)
    rows = summary_rows(run)
    for row in rows:
        mine = [r for r in run.records
                if r["moving"] == row["moving"] and r["planner"] == row["planner"]]
        c = [r for r in mine if r["status"] == "COLLISION"]
        assert row["collision_at_fault"] == sum(r["collision_at_fault"] is True for r in c)
        assert row["collision_standing"] == sum(r["collision_at_fault"] is False for r in c)
        assert row["collision_at_fault"] + row["collision_standing"] == row["collision"]
        ok = [r for r in mine if r["status"] == "SUCCESS"]
        gaps = [r["min_obstacle_distance_m"] for r in ok]
        if row["moving"] == 0 or not ok:
            assert math.isnan(row["min_obstacle_distance_p50_m"])
        else:
            assert row["min_obstacle_distance_p50_m"] == pytest.approx(float(np.median(gaps)))
        if ok:
            assert row["min_static_clearance_p5_m"] == pytest.approx(
                float(np.percentile([r["min_static_clearance_m"] for r in ok], 5)))
    files = write_dynamic_outputs(run, tmp_path / "out")
    md = files["report_md"].read_text()
    assert "collisions: robot at fault / hit standing" in md
    assert "min static clearance (m) p5 / p50" in md and "min disc gap (m) p5 / p50" in md
    assert "## Collisions that were the robot's fault" in md
    summ = _csv(files["summary_csv"])
    assert {"collision_at_fault", "collision_standing", "collision_at_fault_rate",
            "min_static_clearance_p5_m", "min_obstacle_distance_p50_m",
            "shield_replaced_rate", "reached_rate", "time_to_goal_mean_s"} <= set(summ[0])
    eps = _csv(files["episodes_csv"])
    assert {"collision_at_fault", *SHIELD_KEYS, "message", "wall_s"} <= set(eps[0])
    # the database as an older pathfuse wrote it: resumed (nothing runs), still summarised
    _strip_new_values(db)
    old = run_dynamic(cfg, db_path=db)
    assert [r["status"] for r in old.records] == [r["status"] for r in run.records]
    assert all(r["collision_at_fault"] is None and r["shield_asked"] is None
               for r in old.records)
    files = write_dynamic_outputs(old, tmp_path / "old")
    md = files["report_md"].read_text()
    assert "## Collisions that were the robot's fault" not in md
    astar6 = next(s for s in md.splitlines()  # the row of "All outcomes"
                  if s.startswith("| 6 | astar |") and " = " in s)
    assert astar6.rstrip().endswith("| n/a |")  # the shield's share
    row = next(r for r in _csv(files["summary_csv"])
               if r["moving"] == "6" and r["planner"] == "astar")
    assert row["shield_asked"] == "" and row["shield_replaced_rate"] == ""
    disc_hits = sum(r["collision_with"] not in ("", "static") for r in old.records
                    if (r["moving"], r["planner"]) == (6, "astar"))
    assert disc_hits  # unknown after stripping: the split is n/a, not guessed
    assert row["collision_at_fault"] == "" and int(row["collision_fault_unknown"]) == disc_hits
    assert "| n/a | " in astar6
