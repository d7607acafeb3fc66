"""The fusion's walker escape (ours, issue 18; ``fusion.walker_escape``): ``dwa``'s lane
escape (:mod:`pathfuse.planners.controllers.dwa_escape`) on the command of MPPI's sequences
among discs, checked on the IR-SIM training world episode that collided without it
(``examples/irsim-train``; not held out)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pathfuse.planners.controllers.fusion import FusionParams
from pathfuse.result import ConfigError


def test_walker_escape_is_a_switch_of_the_fusion():
    assert FusionParams().walker_escape is True  # on by default since 27 Nov
    assert FusionParams(walker_escape=False).walker_escape is False


irsim = pytest.importorskip("irsim", reason="IR-SIM is an optional extra")

from pathfuse.integrations.irsim import example_worlds_dir  # noqa: E402
from pathfuse.integrations.irsim_run import run_irsim_episode  # noqa: E402

TRAIN = Path(example_worlds_dir()).parent / "irsim-train"


def _least_gap(ep, radius: float) -> float:
    """The least surface gap between the robot and every person over the episode, from the
    recorded positions (independent of the runner's own social metrics)."""
    pos = np.asarray(ep.positions)[:, None, :2]
    ppl = np.asarray(ep.people_positions)[:, :, :2]
    n = min(pos.shape[0], ppl.shape[0])
    d = np.hypot(ppl[:n, :, 0] - pos[:n, :, 0], ppl[:n, :, 1] - pos[:n, :, 1])
    return float((d - radius - np.asarray(ep.people_radii)[None, :]).min())


def test_fusion_leaves_the_lane_of_walkers_that_walk_into_it():
    """walker_escape: among three lanes of walkers coming the robot's way
    (east_three_lanes, seed 1) the fusion's sequences slowed to a stand in a walker's lane
    and it was walked into at about 12.7 s (not at fault).  With the walker escape it turns
    out of the lane before the walker arrives and no one touches it."""
    world = TRAIN / "east_three_lanes.yaml"
    off = run_irsim_episode(world, "fusion", 1, {"walker_escape": False}, time_limit_s=14.0)
    assert off.status.name == "COLLISION" and off.collision_with == "person"
    assert off.collision_at_fault is False  # walked into while standing
    ep = run_irsim_episode(world, "fusion", 1, time_limit_s=14.0)  # the defaults
    assert FusionParams().walker_escape is True
    four = run_irsim_episode(world, "fusion", 1, {"walker_escape_s": 4.0}, time_limit_s=14.0)
    assert four.status.name in ("TIMEOUT", "SUCCESS") and four.collision_with is None
    assert ep.status.name in ("TIMEOUT", "SUCCESS") and ep.collision_with is None
    assert ep.social.min_gap_m > 0.1
    # the world's robot is a disc of 0.25 m; checked from the recorded positions too
    assert _least_gap(off, 0.25) < 0.05 and _least_gap(ep, 0.25) > 0.1


def test_walker_escape_s_is_a_parameter_of_the_fusion():
    assert FusionParams().walker_escape_s == 3.5  # dwa's lane_escape_s is 4
    assert FusionParams(walker_escape_s=4.0).walker_escape_s == 4.0
    with pytest.raises(ConfigError, match="walker_escape_s"):
        FusionParams(walker_escape_s=0.0)


def test_the_default_escape_passes_the_third_pair():
    """walker_escape_s (ours; 3.5 s by default): east_three_lanes seed 3, the fusion's
    other training collision: it passes the second pair below, along the wall, in the lane
    of a third pair sensed when there is no spot left to stand, and is walked into standing
    at about 9.5 s (with the escape's old 4 s horizon at 10.1 s).  With 3.5 s the escape,
    set off a tick later, flees west ahead of the second pair for 3 s and then turns north
    behind its upper walker, 1.5 m ahead of its lower one, before the third pair comes; no
    one touches it.  A replayed case, not a rule: on seeds 8-23 of the three-lane worlds
    3.5 s is not better than 4 s (docs/guide/people.md)."""
    world = TRAIN / "east_three_lanes.yaml"
    off = run_irsim_episode(world, "fusion", 3, {"seed": 3, "walker_escape": False},
                            time_limit_s=14.0)
    assert off.status.name == "COLLISION" and off.collision_with == "person"
    assert off.collision_at_fault is False
    four = run_irsim_episode(world, "fusion", 3,
                             {"seed": 3, "walker_escape": True, "walker_escape_s": 4.0},
                             time_limit_s=14.0)
    assert four.status.name == "COLLISION" and four.collision_at_fault is False
    ep = run_irsim_episode(world, "fusion", 3, {"seed": 3}, time_limit_s=14.0)  # defaults
    assert ep.status.name in ("TIMEOUT", "SUCCESS") and ep.collision_with is None
    assert _least_gap(off, 0.25) < 0.05 and _least_gap(ep, 0.25) > 0.1
