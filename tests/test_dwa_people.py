"""dwa among people in IR-SIM's worlds (issue 18): each mechanism of ours on an episode that
failed without it, and failing again with its parameter off."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("irsim", reason="IR-SIM is an optional extra: pip install 'pathfuse[irsim]'")

from pathfuse.integrations.irsim import example_worlds_dir  # noqa: E402
from pathfuse.integrations.irsim_run import run_irsim_episode  # noqa: E402
from pathfuse.planners.controllers.social import PassingSides, path_sides  # noqa: E402

WORLDS = Path(example_worlds_dir())


def _ok(ep) -> bool:
    return ep.status.name == "SUCCESS" and ep.social.min_gap_m >= 0.3


def test_dwa_overtakes_the_slow_walker():
    """social_replan: the A* path replanned around the walker with personal space lets dwa
    pass it (overtake_slow_walker, seed 2: it followed at 0.4 m/s for 60 s before)."""
    world = WORLDS / "overtake_slow_walker.yaml"
    ep = run_irsim_episode(world, "dwa", 2, time_limit_s=30.0)
    assert _ok(ep)
    off = run_irsim_episode(world, "dwa", 2, {"social_replan": False}, time_limit_s=30.0)
    assert off.status.name == "TIMEOUT"
    # it is still behind the walker going its way (the first person, at 0.4 m/s)
    assert off.positions[-1, 0] < off.people_positions[-1, 0, 0]


def test_dwa_waits_outside_the_lane_of_a_head_on_pair():
    """dwell_s (on in dwa now): dwa stood in front of the head-on pair, in their lane, and
    was walked into (corridor_head_on, seed 0).  The ablation is without the lane escape
    (dwa_escape), which came later and saves this episode on its own too."""
    world = WORLDS / "corridor_head_on.yaml"
    ep = run_irsim_episode(world, "dwa", 0)
    assert _ok(ep)
    off = run_irsim_episode(world, "dwa", 0, {"dwell_s": 0.0, "lane_escape": False},
                            time_limit_s=10.0)
    assert off.status.name == "COLLISION" and off.collision_with == "person"


def test_path_sides_keeps_dwa_from_standing_in_the_rvo_crowd():
    """path_sides (and the immediate replan on a new disc that comes with it): without it dwa
    stood turning on the spot among the RVO crowd and was walked into (rvo_crowd, seed 2);
    the group rule itself is checked in test_path_sides_and_a_group_conflict."""
    world = WORLDS / "rvo_crowd.yaml"
    ep = run_irsim_episode(world, "dwa", 2)
    assert _ok(ep)
    off = run_irsim_episode(world, "dwa", 2, {"path_sides": False}, time_limit_s=12.0)
    assert off.status.name == "COLLISION"


def test_dwa_leaves_its_clearance_along_the_wall():
    """inside_clearance: after dodging walkers dwa stood inside its own clearance by the
    wall and found no admissible sample for the rest of the episode (sfm_flows, seed 0).  The
    ablation is without the lane escape (dwa_escape), which came later: with it, the escape
    moves the robot on from there too."""
    world = WORLDS / "sfm_flows.yaml"
    ep = run_irsim_episode(world, "dwa", 0, time_limit_s=45.0)
    assert ep.status.name == "SUCCESS"
    off = run_irsim_episode(world, "dwa", 0, {"inside_clearance": False, "lane_escape": False},
                            time_limit_s=20.0)
    assert off.status.name == "TIMEOUT"
    assert np.hypot(*(off.positions[-1] - off.positions[-60])) < 0.05  # standing


def test_path_sides_and_a_group_conflict():
    pts = np.array([[0.0, 3.0], [4.0, 3.0], [5.0, 1.8], [7.0, 1.8], [8.0, 3.0], [12.0, 3.0]])
    dpos = np.array([[6.0, 2.8], [6.0, 3.4]])  # a pair side by side; the path passes below
    drad = np.full(2, 0.25)
    pref = path_sides(pts, 0, dpos, drad, 0.25, 0.5)
    assert pref.tolist() == [1.0, 1.0]
    ps = PassingSides(0.5)
    ids = np.array([1, 2])
    ps.committed = {1: -1.0}  # the first was committed alone, above it
    chosen = np.array([[1.0, 0.4], [1.0, 0.4]])
    ps.update(ids, chosen, dpos, (3.0, 3.0), (1.0, 0.0), drad, 0.25, pref)
    assert ps.committed == {1: 1.0, 2: 1.0}  # one side for the pair, the path's
    ps.committed = {1: -1.0}
    ps.update(ids, chosen, dpos, (3.0, 3.0), (1.0, 0.0), drad, 0.25)  # without: between
    assert ps.committed == {1: -1.0, 2: 1.0}
