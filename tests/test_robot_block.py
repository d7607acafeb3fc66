"""One robot type: :class:`pathfuse.robot.RobotModel` is what a scenario holds, what a
``robot:`` block reads into and writes back from, and it records which keys were set, so a
scenario file round-trips exactly (the unset keys stay unset and are not written)."""

from __future__ import annotations

import math
import pickle

import pytest
import yaml

from pathfuse import ConfigError, simulate
from pathfuse.robot import DIFF_DRIVE_DEFAULTS, FIELDS, ROBOT_KEYS, RobotModel
from pathfuse.world import ScenarioError, load_scenario, save_scenario

ROWS = {"rows": ["........", "........", "........"]}


def _doc(robot=None):
    d = {"map": ROWS, "start": [0.5, 1.5], "goal": [7.5, 1.5]}
    if robot is not None:
        d["robot"] = robot
    return d


@pytest.mark.parametrize("block", [
    None,
    {},
    {"model": "diff-drive", "max_yaw_rate": 1.0},
    {"radius": 0.3, "inflation": 0.0, "shield": False},
    {"model": "diff-drive", "min_speed": -0.2, "max_accel": None, "heading": 0.5},
])
def test_a_scenario_round_trips_with_its_unset_keys_unset(block, tmp_path):
    sc = load_scenario(_doc(block))
    assert isinstance(sc.robot, RobotModel)
    written = {k: v for k, v in (block or {}).items() if v is not None}
    assert sc.robot.to_dict() == written               # only the keys the file set
    d = sc.to_dict()
    assert d["robot"] == written
    again = load_scenario(yaml.safe_load(yaml.safe_dump(d)))
    assert again.robot == sc.robot and again.to_dict() == d
    path = save_scenario(sc, tmp_path / "sc.yaml")
    from_file = load_scenario(path)
    assert from_file.robot == sc.robot and from_file.robot.explicit == sc.robot.explicit
    assert yaml.safe_load(path.read_text())["robot"] == written


def test_unset_limits_take_the_kind_defaults_and_follow_a_change_of_kind():
    rb = RobotModel.from_dict({"max_yaw_rate": 1.5})
    assert (rb.max_accel_mps2, rb.max_yaw_rate_radps, rb.inflation_m) == (math.inf, 1.5, 0.0)
    dd = rb.replace(kind="diff-drive")
    assert dd.max_accel_mps2 == DIFF_DRIVE_DEFAULTS["max_accel_mps2"]
    assert dd.inflation_m == DIFF_DRIVE_DEFAULTS["inflation_m"]
    assert dd.max_yaw_rate_radps == 1.5                          # set: kept
    assert dd.explicit == ("kind", "max_yaw_rate_radps")
    assert dd.replace(max_yaw_rate_radps=None).max_yaw_rate_radps == 2.0   # None: unset again
    # the CLI's --robot model=diff-drive merges blocks the same way
    sc = load_scenario(_doc({"max_yaw_rate": 1.5}))
    assert RobotModel.from_dict({**sc.robot.to_dict(), "model": "diff-drive"}) == dd
    assert RobotModel(kind="diff-drive") == RobotModel.diff_drive() \
        == RobotModel.from_dict({"model": "diff-drive"})


def test_the_robot_records_the_fields_it_was_given():
    assert RobotModel().explicit == () and RobotModel().to_dict() == {}
    rb = RobotModel(radius_m=0.2, clearance_m=0.1, kind="holonomic")
    assert rb.explicit == ("kind", "radius_m", "clearance_m")
    assert rb.to_dict() == {"radius": 0.2, "model": "holonomic", "clearance": 0.1}
    assert rb != RobotModel(clearance_m=0.1)                     # set alike, or not equal
    assert set(FIELDS) == {f for f in RobotModel.__dataclass_fields__ if f != "explicit"}
    assert len(ROBOT_KEYS) == len(FIELDS)
    # an explicit "no limit" (inf) survives YAML
    free = RobotModel.diff_drive(max_yaw_rate_radps=math.inf)
    assert RobotModel.from_dict(yaml.safe_load(yaml.safe_dump(free.to_dict()))) == free
    # process pools pickle it
    assert pickle.loads(pickle.dumps(rb)) == rb and pickle.loads(pickle.dumps(rb)).explicit


def test_keyword_only_and_errors_name_the_key_and_the_value():
    with pytest.raises(TypeError):
        RobotModel(0.2)  # type: ignore[misc]
    with pytest.raises(ConfigError, match=r"^robot\.radius_m: must be a number >= 0, got -1$"):
        RobotModel(radius_m=-1)
    with pytest.raises(ConfigError, match=r"^robot\.max_yaw_rate_radps: must be a number > 0 "
                                          r"\(inf: no limit\), got 0$"):
        RobotModel(max_yaw_rate_radps=0)
    with pytest.raises(ConfigError, match=r"^robot\.radius: must be a number >= 0, got -1$"):
        RobotModel.from_dict({"radius": -1})
    with pytest.raises(ScenarioError, match=r"robot\.max_accel: must be a number > 0 "
                                            r"\(inf: no limit\), got 'fast'"):
        load_scenario(_doc({"model": "diff-drive", "max_accel": "fast"}))
    with pytest.raises(ConfigError, match=r"^robot\.min_speed_mps: must be 0 for a holonomic"):
        RobotModel(min_speed_mps=-0.5)
    with pytest.raises(ConfigError, match=r"^robot\.size_m: not a field"):
        RobotModel().replace(size_m=1)


def test_simulate_takes_the_one_type_or_a_block_alike():
    sc = _doc({"radius": 0.2})
    a = simulate(sc, planner="dwa", robot=RobotModel.diff_drive(radius_m=0.2))
    b = simulate(sc, planner="dwa", robot={"model": "diff-drive", "radius": 0.2})
    assert a.robot == b.robot and a.robot.is_diff_drive
    assert a.positions.tolist() == b.positions.tolist()
