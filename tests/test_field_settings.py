"""The field loops' named settings (issue 17): each parameter reaches its loop under its own
name, none in another's place (the numbered slots they replace meant one thing in one loop
and another in the next)."""

import math

import numpy as np

from pathfuse.costmap import costmap_for
from pathfuse.field.kernels import CODE_RUNNING, S_SUB, STATIC, field_loop
from pathfuse.field.repulsion import AHEAD_PAPER_X
from pathfuse.field.settings import pack_field
from pathfuse.grid import GridMap
from pathfuse.planners.controllers.apf import APFController, APFParams
from pathfuse.planners.controllers.fusion import FusionController, FusionParams
from pathfuse.planners.controllers.refs import Ref6Controller, Ref6Params
from pathfuse.problem import Problem

GRID = GridMap.from_rows(["........"] * 6)
PATH = np.array([[0.5, 0.5], [2.5, 1.5], [4.5, 3.5], [7.5, 5.5]])


class _Path:
    waypoints = PATH


def _problem(**kw):
    return Problem.create(GRID, (0.5, 0.5), (7.5, 5.5), 0.15, clearance_m=0.07, **kw)


def _shared(**kw):
    """Distinct values for the parameters every field controller has."""
    return dict(k_att=41.0, k_rep=21.0, rho0_m=2.1, step_m=0.11, goal_tolerance_m=0.13,
                stall_steps=17, stall_distance_m=0.019, safe_step=False, stall_exit=False,
                static_repulsion="boundary", boundary_offset_m=0.37, k_rep_moving=3.0,
                rho0_moving_m=1.9, repulsion="velocity", a_max=2.3, swerve=0.4, **kw)


def _check_shared(c, s):
    assert (s.goal_x_m, s.goal_y_m) == (7.5, 5.5)
    assert (s.k_att, s.k_rep, s.rho0_m, s.step_m, s.goal_tolerance_m) == \
        (41.0, 21.0, 2.1, 0.11, 0.13)
    assert (s.stall_steps, s.stall_distance_m, s.safe_step, s.stall_exit) == \
        (17, 0.019, False, False)
    assert (s.boundary, s.boundary_offset_m, s.margin_m) == (True, 0.37, 0.07)
    d = c.disc_cfg
    assert (d.k_rep, d.rho0_m, d.velocity_aware, d.a_max_mps2, d.swerve) == \
        (3.0, 1.9, True, 2.3, 0.4)
    assert c.costmap.radius_m == 0.15 and c.costmap.clear_m == c.clear_m
    assert c.costmap.occ is GRID.occupied


def test_fusion_settings_carry_each_parameter_by_name():
    p = FusionParams(**_shared(r1_m=1.3, r2_m=1.7, ahead="paper-x", escape=False,
                               escape_points=5))
    c = FusionController(_problem(), p, _Path())
    s = c.settings
    _check_shared(c, s)
    assert (s.r1_m, s.r2_m, s.ahead, s.escape, s.escape_points, s.drive) == \
        (1.3, 1.7, AHEAD_PAPER_X, False, 5, False)
    assert s.backoff_window_m == 17 * 0.11 + 2.0 * (1.3 + 1.0)
    assert c.disc_cfg.reach_m == 1.7  # the discs repel within r2, as the cells do
    online = FusionController(_problem(), p, _Path(), dt=0.1, max_speed=1.0)
    assert online.settings.drive and online.settings.step_m == 0.1


def test_field_settings_carry_each_parameter_by_name():
    p = Ref6Params(**_shared(subgoal_tolerance_m=0.29, rep_exponent=3.0, rep_scale_m=1.1,
                             rep_target="goal"))
    c = Ref6Controller(_problem(), p, _Path())
    s = c.settings
    _check_shared(c, s)
    assert (s.subgoal_tolerance_m, s.rep_exponent, s.rep_scale_m) == (0.29, 3.0, 1.1)
    assert s.improved and s.rep_to_goal and math.isinf(c.disc_cfg.reach_m)
    a = APFController(_problem(), APFParams(**_shared())).settings
    assert (a.subgoal_tolerance_m, a.improved, a.rep_to_goal) == (0.0, False, False)


def test_field_loop_passes_a_subgoal_within_the_subgoal_tolerance_only():
    """The loop reads the sub-goal tolerance, not a neighbour: the first sub-goal, 1 m
    from the start, is passed before any move with a tolerance of 1.5 m and not with
    0.5 m, whatever the other distances (goal tolerance, stall distance, Ge-Cui scale)."""
    cm = costmap_for(GRID, 0.0, lattice=False)
    subs = np.array([[1.5, 0.5], [7.5, 5.5]])
    for tol, passed in ((1.5, 1), (0.5, 0)):
        s = pack_field((7.5, 5.5), 40.0, 20.0, 2.0, 0.1, 5.0 - tol, 3, 5.0 - tol, tol, True,
                       False, 2.0, 5.0 - tol)
        buf = np.zeros((8, 2))
        buf[0] = (0.5, 0.5)
        state = np.zeros(1, dtype=np.int64)
        ds = APFController(_problem(), APFParams()).disc_cfg
        _, n, code, steps = field_loop(buf, 1, 0, cm, subs, state, s, ds, *STATIC)
        assert (int(state[S_SUB]), n, code, steps) == (passed, 1, CODE_RUNNING, 0)
