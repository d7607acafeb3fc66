"""The fusion's evasion out of a walker's swept lane (ours, ``evade``;
pathfuse.planners.controllers.evade)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pathfuse.costmap import make_costmap
from pathfuse.planners.controllers.evade import (
    EVADE_HEADINGS,
    Evader,
    evade_fan,
    sequence_gap,
)
from pathfuse.planners.controllers.mppi_kernel import pack_mppi
from pathfuse.sweep import unicycle_pose


def _settings():
    # dt 0.1, model step 0.1, v in [0, 1], 2 m/s^2, 2 rad/s, 4 rad/s^2, diff-drive
    return pack_mppi(0.1, 0.1, 0.0, 1.0, 2.0, 2.0, 4.0, False, 0.0, 0.3, 1000.0, 5.0, 0.55,
                     10.0, 2.0, 5.0, 5.0, 1.4, 1.0, 0.6, 100.0, 5.0, 0.3, 1.0, 5.0, 0.2, 0.4,
                     1.0, 19.0, 5.0, 5.0, 0.4, True)


def _open(n=20, res=0.5, radius=0.25):
    return make_costmap(np.zeros((n, n), dtype=np.bool_), radius, resolution_m=res)


def _brute_gap(seq, x, y, th, dpos, dvel, drad, radius, tail_s, spread):
    """The same quantity by plain Python: poses after each step, the stand sampled finely."""
    best = math.inf
    t = 0.0
    for k in range(seq.shape[0]):
        x, y, th = unicycle_pose(x, y, th, float(seq[k, 0]), float(seq[k, 1]), 0.1)
        t += 0.1
        for i in range(drad.shape[0]):
            c = dpos[i] + dvel[i] * t
            best = min(best, math.hypot(x - c[0], y - c[1]) - radius - drad[i] - spread * t)
    t_end = t
    for u in np.linspace(0.0, tail_s, 20001):
        for i in range(drad.shape[0]):
            c = dpos[i] + dvel[i] * (t_end + u)
            best = min(best, math.hypot(x - c[0], y - c[1]) - radius - drad[i]
                       - spread * (t_end + tail_s))
    return best


@pytest.mark.parametrize("seed", range(6))
def test_sequence_gap_against_a_brute_force_rollout(seed):
    rng = np.random.default_rng(seed)
    cm = _open(40, 0.5)
    seq = np.column_stack([rng.uniform(0.0, 1.0, 12), rng.uniform(-2.0, 2.0, 12)])
    dpos = rng.uniform(6.0, 14.0, (3, 2))
    dvel = rng.uniform(-0.8, 0.8, (3, 2))
    drad = rng.uniform(0.2, 0.4, 3)
    spread = float(rng.choice([0.0, 0.2]))
    th = float(rng.uniform(-3.0, 3.0))
    got = sequence_gap(cm, 0.1, 0.1, seq, 10.0, 10.0, th, dpos, dvel, drad, 2.0, spread)
    want = _brute_gap(seq, 10.0, 10.0, th, dpos, dvel, drad, 0.25, 2.0, spread)
    assert got <= want + 1e-9            # the stand's closest approach is exact, not sampled
    assert got == pytest.approx(want, abs=1e-4)


def test_sequence_gap_is_minus_inf_into_a_wall():
    occ = np.zeros((20, 20), dtype=np.bool_)
    occ[:, 12] = True                     # a wall at x = 6 m
    cm = make_costmap(occ, 0.25, resolution_m=0.5)
    seq = np.zeros((10, 2))
    seq[:, 0] = 1.0                       # 1 m east from x = 5.2
    none = (np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0))
    assert sequence_gap(cm, 0.1, 0.1, seq, 5.2, 5.0, 0.0, *none, 2.0) == -math.inf
    assert sequence_gap(cm, 0.1, 0.1, seq, 5.2, 5.0, math.pi, *none, 2.0) == math.inf


def _head_on():
    # a robot standing at (5, 5) facing east; a disc 1.5 m east coming at it at 0.6 m/s
    return (np.array([[6.5, 5.0]]), np.array([[-0.6, 0.0]]), np.array([0.25]))


def test_evader_leaves_the_lane_and_only_by_an_escape_the_shield_passes():
    cm = _open()
    f = _settings()
    dpos, dvel, drad = _head_on()
    stand = np.zeros((25, 2))
    assert sequence_gap(cm, 0.1, 0.1, stand, 5.0, 5.0, 0.0, dpos, dvel, drad, 2.0) < 0
    ev = Evader((9.0, 5.0))
    plan = stand.copy()
    assert ev.choose(cm, f, 5.0, 5.0, 0.0, 0.0, 0.0, plan, dpos, dvel, drad)
    # the escape clears the disc's sweep over the rollout and the stand after it
    assert sequence_gap(cm, 0.1, 0.1, plan, 5.0, 5.0, 0.0, dpos, dvel, drad, 2.0) >= 0.1
    assert ev.evasions == 1 and math.isfinite(ev.heading)
    # a shield that holds every escape back: the plan stays as it was
    asked: list[tuple[float, float]] = []
    ev2 = Evader((9.0, 5.0))
    plan2 = stand.copy()

    def never(v, w):
        asked.append((v, w))
        return False

    assert not ev2.choose(cm, f, 5.0, 5.0, 0.0, 0.0, 0.0, plan2, dpos, dvel, drad, never)
    assert np.array_equal(plan2, stand) and ev2.evasions == 0
    assert 1 <= len(asked) <= EVADE_HEADINGS
    # nothing to escape: the plan is not touched
    ev3 = Evader((9.0, 5.0))
    away = (dpos, -dvel, drad)
    plan3 = stand.copy()
    assert not ev3.choose(cm, f, 5.0, 5.0, 0.0, 0.0, 0.0, plan3, *away)
    assert np.array_equal(plan3, stand)


def test_a_fan_heading_into_a_wall_does_not_block_the_escape():
    """Regression (a bug until issue 17's walked-into round): a fan sequence into a wall has
    the gap -inf, and numba's math.floor(-inf) negated overflowed, ranking it first; the
    choice then stopped at it and took no escape."""
    occ = np.zeros((20, 20), dtype=np.bool_)
    occ[:, 7] = True                      # a wall at x = 3.5-4 m, behind the robot
    cm = make_costmap(occ, 0.25, resolution_m=0.5)
    f = _settings()
    dpos, dvel, drad = _head_on()
    stand = np.zeros((25, 2))
    seqs = np.empty((EVADE_HEADINGS, 25, 2))
    gaps = np.empty(EVADE_HEADINGS)
    heads = np.empty(EVADE_HEADINGS)
    order = np.empty(EVADE_HEADINGS, dtype=np.int64)
    evade_fan(cm, f, 5.0, 5.0, 0.0, 0.0, 0.0, dpos, dvel, drad, 3.0, 0.2, 0.5, 9.0, 5.0,
              math.nan, 0.1, seqs, gaps, heads, order)
    assert (gaps == -math.inf).any()      # some headings meet the wall
    assert gaps[order[0]] == gaps.max()   # the best gap is ranked first
    ev = Evader((9.0, 5.0))
    plan = stand.copy()
    assert ev.choose(cm, f, 5.0, 5.0, 0.0, 0.0, 0.0, plan, dpos, dvel, drad)
    assert sequence_gap(cm, 0.1, 0.1, plan, 5.0, 5.0, 0.0, dpos, dvel, drad, 2.0) >= 0.1


def test_fusion_with_evade_passes_a_head_on_disc_through_the_shield():
    """The switch reaches the controller: with ``evade`` on, the fusion's diff-drive robot
    passes the shipped head-on scenario; every command went through the shield (its counts
    add up to the ticks) and nothing was hit."""
    from pathlib import Path

    from pathfuse.world import simulate

    sc = str(Path(__file__).resolve().parents[1] / "examples" / "scenarios" / "head_on.yaml")
    robot = {"model": "diff-drive", "radius": 0.2, "max_speed": 1.0, "sensing_radius": 3.0}
    ep = simulate(sc, planner={"name": "fusion", "params": {"evade": True}}, robot=robot)
    assert ep.status.name == "SUCCESS", ep.message
    assert sum(ep.shield_counts.values()) == ep.n_ticks
    # an independent check of the gap to the disc at every tick
    gaps = np.hypot(*(ep.positions[:, None, :] - ep.obstacle_positions).transpose(2, 0, 1))
    assert float((gaps - ep.obstacle_radii - 0.2).min()) > 0.0


def test_the_trigger_counts_only_the_discs_marked():
    """Ours (``evade_steady``): a disc not marked (seen to wander) does not set the escape off,
    a marked one does; the fusion's switch is off by default."""
    from pathfuse.planners.controllers.fusion import FusionParams

    cm = _open()
    f = _settings()
    dpos, dvel, drad = _head_on()
    stand = np.zeros((25, 2))
    plan = stand.copy()
    assert not Evader((9.0, 5.0)).choose(cm, f, 5.0, 5.0, 0.0, 0.0, 0.0, plan, dpos, dvel,
                                         drad, None, np.array([False]))
    assert np.array_equal(plan, stand)
    assert Evader((9.0, 5.0)).choose(cm, f, 5.0, 5.0, 0.0, 0.0, 0.0, plan, dpos, dvel, drad,
                                     None, np.array([True]))
    assert FusionParams().evade_steady is False
