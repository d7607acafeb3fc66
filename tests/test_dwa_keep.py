"""The keep critic's defaults (issue 17's clearance round): exact values of its term.

A straight rollout runs parallel to a long wall at a known gap; the critic's term is the
rollout's cost with the critic on less its cost with it off (every other critic is the
same), and must equal ``weight x min(((want - gap) / max(want, KEEP_FLOOR))^2, 1)`` with
``want = min(path gap, keep_m)``.  With the defaults (10, 0.15 m) a pass 0.2 m from the wall
where the path keeps 0.3 m costs nothing (it cost 0.56 with the old 5, 0.3 m: the robot
slowed and swerved in the open), and at a narrowing that the path passes at 8 cm the term is
twice the old one (the narrowings are where BARN's least clearance is set).
"""

from __future__ import annotations

import numpy as np
import pytest

from pathfuse.costmap import costmap_for
from pathfuse.field.pathing import polyline_cumlen
from pathfuse.grid import GridMap
from pathfuse.planners.controllers.dwa import DWAParams
from pathfuse.planners.controllers.dwa_checks import NO_NEAR, path_blocks
from pathfuse.planners.controllers.dwa_kernel import (
    KEEP_FLOOR,
    KEEP_M,
    KEEP_WEIGHT,
    _rollout,
    pack_dwa,
)
from pathfuse.planners.controllers.dwa_route import _local_goal
from pathfuse.planners.controllers.social import EVERY_DISC

RES = 0.05
RADIUS = 0.333
WALL_TOP = 0.5  # the wall fills rows 0-9: its squares end at y = 0.5


def _costmap():
    occ = np.zeros((60, 400), dtype=np.bool_)  # 20 m x 3 m; the top edge is 2.5 m away
    occ[:10, :] = True
    return costmap_for(GridMap(occ, origin=(0.0, 0.0), resolution=RES), RADIUS)


def _settings(w_keep: float, keep_m: float):
    p = DWAParams()
    return pack_dwa(0.1, 0.0, 2.0, 2.0, 2.0, 4.0, 0.0, p.horizon_s, p.sim_step_s, p.v_samples,
                    p.w_samples, p.path_weight, p.goal_weight, p.heading_weight,
                    p.speed_weight, p.obstacle_weight, p.moving_weight, p.obstacle_range_m,
                    p.lookahead_m, p.inflation_decay_m, False, True,
                    w_align=p.path_align_weight, near_s=p.keep_horizon_s, w_keep=w_keep,
                    keep_m=keep_m)


def _cost(f, gap: float, gref: float, v: float = 1.0) -> float:
    """The cost of a straight rollout at speed ``v`` along +x, ``gap`` from the wall."""
    cm = _costmap()
    y = WALL_TOP + RADIUS + gap
    pts = np.array([[2.0, y], [18.0, y]])
    cum = polyline_cumlen(pts)
    jg = _local_goal(pts, cum, 0, f.max_speed_mps * f.horizon_s + f.lookahead_m + 1.0)
    bb = path_blocks(pts, 0, jg)
    out = np.zeros(3)
    none2 = np.zeros((0, 2))
    _rollout(cm, NO_NEAR, f, cm.clear_m, gref, 2.0, y, 0.0, v, 0.0, pts, cum, 0, jg, bb,
             none2, none2, np.zeros(0), out, 1.0, 0.0, np.zeros(0), none2, np.zeros(0),
             EVERY_DISC)
    assert out[1] == 1.0 and out[2] == 1.0  # admissible
    return float(out[0])


def _term(w_keep: float, keep_m: float, gap: float, gref: float) -> float:
    return _cost(_settings(w_keep, keep_m), gap, gref) - _cost(_settings(0.0, keep_m), gap,
                                                                gref)


def _expected(w_keep: float, keep_m: float, gap: float, gref: float) -> float:
    want = min(gref, keep_m)
    short = want - gap
    return w_keep * min((short / max(want, KEEP_FLOOR)) ** 2, 1.0) if short > 0 else 0.0


def test_the_defaults_are_the_new_ones() -> None:
    from pathfuse.planners.controllers.fusion import FusionParams

    p, fp = DWAParams(), FusionParams()
    assert (p.keep_weight, p.keep_m) == (KEEP_WEIGHT, KEEP_M) == (10.0, 0.15)
    assert (fp.keep_weight, fp.keep_m) == (KEEP_WEIGHT, KEEP_M)


@pytest.mark.parametrize("gap, gref", [(0.2, 0.3), (0.1, 0.3), (0.04, 0.08), (0.07, 0.08),
                                       (0.01, 0.03), (0.16, 1.0)])
def test_keep_term_is_exact(gap: float, gref: float) -> None:
    for w_keep, keep_m in ((KEEP_WEIGHT, KEEP_M), (5.0, 0.3)):
        assert _term(w_keep, keep_m, gap, gref) == pytest.approx(
            _expected(w_keep, keep_m, gap, gref), rel=1e-9, abs=1e-12)


def test_open_ground_is_free_and_narrowings_weigh_twice() -> None:
    # in the open (the path keeps 0.3 m), a pass at 0.2 m: free now, 5 x (0.1 / 0.3)^2 before
    assert _term(KEEP_WEIGHT, KEEP_M, 0.2, 0.3) == pytest.approx(0.0, abs=1e-12)
    assert _term(5.0, 0.3, 0.2, 0.3) == pytest.approx(5.0 / 9.0, rel=1e-9)
    # at a narrowing the path passes at 8 cm, a pass at 4 cm: 10 x 0.25 now, 5 x 0.25 before
    assert _term(KEEP_WEIGHT, KEEP_M, 0.04, 0.08) == pytest.approx(2.5, rel=1e-9)
    assert _term(5.0, 0.3, 0.04, 0.08) == pytest.approx(1.25, rel=1e-9)


def test_fusion_window_takes_the_fusions_keep_params() -> None:
    from pathfuse.planners.controllers.fusion_window import ForceWindow
    from pathfuse.problem import Problem
    from pathfuse.robot import RobotModel

    occ = np.zeros((20, 20), dtype=np.bool_)
    g = GridMap(occ, origin=(0.0, 0.0), resolution=0.1)
    pb = Problem.create(g, (0.5, 0.5), (1.5, 1.5), 0.2,
                        robot=RobotModel.diff_drive(radius_m=0.2))
    dflt = ForceWindow(pb, 0.1, among_discs="window")
    assert (dflt.f.keep_weight, dflt.f.keep_m) == (KEEP_WEIGHT, KEEP_M)
    old = ForceWindow(pb, 0.1, among_discs="window", keep=(5.0, 0.3))
    assert (old.f.keep_weight, old.f.keep_m) == (5.0, 0.3)


def test_fusion_params_reach_its_window() -> None:
    from pathfuse.planners.controllers.fusion import FusionController, FusionParams
    from pathfuse.problem import Problem
    from pathfuse.robot import RobotModel

    g = GridMap(np.zeros((20, 20), dtype=np.bool_), origin=(0.0, 0.0), resolution=0.1)
    pb = Problem.create(g, (0.5, 0.5), (1.5, 1.5), 0.2,
                        robot=RobotModel.diff_drive(radius_m=0.2))

    class _Plan:
        waypoints = np.array([[0.5, 0.5], [1.5, 1.5]])

    c = FusionController(pb, FusionParams(keep_weight=3.0, keep_m=0.2, among_discs="window"),
                         _Plan(), dt=0.1, max_speed=1.0)
    assert (c._window.f.keep_weight, c._window.f.keep_m) == (3.0, 0.2)
    c = FusionController(pb, FusionParams(among_discs="window"), _Plan(), dt=0.1,
                         max_speed=1.0)
    assert (c._window.f.keep_weight, c._window.f.keep_m) == (KEEP_WEIGHT, KEEP_M)
