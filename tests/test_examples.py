"""The shipped scenario examples end as their comments (and the README) say."""

from __future__ import annotations

from pathlib import Path

import pytest

import pathfuse

EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "scenarios"


@pytest.mark.parametrize("planner, params, status, t_s, hit", [
    (None, {}, "COLLISION", 13.7, 2),                       # the file's own: astar-replan, 1 Hz
    ("astar-replan", {"replan_period_s": 0.2}, "COLLISION", 13.4, 2),
    ("astar", {}, "SUCCESS", 28.8, None),
    ("ref6", {}, "SUCCESS", 28.9, None),
    ("ref7", {}, "SUCCESS", 28.7, None),
    ("apf", {}, "SUCCESS", 52.1, None),
    ("fusion", {}, "LOCAL_MINIMUM", 40.5, None),
])
def test_warehouse_patrol_shows_the_failure_its_comment_describes(planner, params, status, t_s,
                                                                   hit):
    path = EXAMPLES / "warehouse_patrol.yaml"
    assert "shows a FAILURE, on purpose" in path.read_text()
    choice = None if planner is None else {"name": planner, "params": params}
    ep = pathfuse.simulate(str(path), planner=choice)
    assert ep.status.name == status, ep.message
    assert ep.times[-1] == pytest.approx(t_s, abs=1e-9)
    if hit is not None:
        assert str(ep.collision_with) == str(hit)
        assert ep.collision_at_fault is False  # the shield stopped the robot in time


def test_head_on_astar_collides_and_fusion_passes():
    path = EXAMPLES / "head_on.yaml"
    ep = pathfuse.simulate(str(path), planner="astar")
    assert ep.status.name == "COLLISION" and ep.collision_at_fault is False
    # without the shield the blind follower walks into the disc itself
    ep = pathfuse.simulate(str(path), planner="astar", robot={"radius": 0.2, "shield": False})
    assert ep.status.name == "COLLISION" and ep.collision_at_fault is True
    assert pathfuse.simulate(str(path), planner="fusion").status.name == "SUCCESS"
