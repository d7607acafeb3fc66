"""The parameter groups the planners share, declared once with their defaults.

Every planner's parameters are one frozen dataclass built from these
groups; each field carries its constraint, unit and help text
(:func:`pathfuse.validate.param`), which ``pathfuse planners`` prints and
:func:`pathfuse.validate.check_fields` enforces.  Offline (``plan()``) and
online (``simulate()``) use the same instance and the same defaults.
"""

from __future__ import annotations

import dataclasses
import types
from dataclasses import dataclass
from typing import Any

from pathfuse.field.forces import K_ATT, K_REP, RHO0_M
from pathfuse.field.repulsion import BOUNDARY_OFFSET_M
from pathfuse.limits import MAX_SEED
from pathfuse.result import ConfigError
from pathfuse.search.astar import HEURISTICS
from pathfuse.validate import ParamSpec, check_fields, param

KEEP_WEIGHT = 10.0
"""The keep critic's default weight (``dwa.keep_weight`` and the fusion's window; 5 before
issue 17's clearance round, 26 Nov 2026)."""
KEEP_M = 0.15
"""The most gap the keep critic asks for by default (``dwa.keep_m``, m; 0.3 before issue 17's
clearance round).  The critic asks for the gap the global path keeps ahead, up to this: at a
narrowing the path's own gap (on BARN 0.04-0.1 m) is asked for whatever ``keep_m`` is, so a
smaller cap leaves the narrowings' term as it was and stops charging samples that pass
0.15-0.3 m from a cylinder in the open, which made the robot slow and swerve there; that is
what lets the weight double at no cost in speed (docs/results/barn.md)."""

__all__ = ["Checked", "GlobalChoice", "GlobalAStarParams", "FieldParams", "DiscParams",
           "PursuitParams", "PersonalSpaceParams", "SocialParams", "BOUNDS", "KEEP_M",
           "KEEP_WEIGHT"]

_BIG = 1e6  # gains, weights and costs
BOUNDS: dict[str, tuple[float | None, float]] = {
    # the global A* and replanning (astar.py)
    "replan_period_s": (None, 3600), "margin_m": (None, 100),
    # the fusion (fusion.py) and the references (refs.py)
    "r1_m": (None, 100), "r2_m": (None, 100), "escape_points": (None, 1000),
    "subgoal_tolerance_m": (None, 100), "rep_exponent": (None, 10),
    "rep_scale_m": (None, 1000), "segment_length_m": (None, 1000),
    "segment_points": (None, 10_000),
    # DWA (dwa.py): one tick rolls out v_samples x w_samples x horizon_s / sim_step_s steps
    "v_samples": (None, 64), "w_samples": (None, 128), "horizon_s": (None, 10),
    "sim_step_s": (0.001, 1), "dt_s": (0.001, 1), "path_weight": (None, _BIG),
    "goal_weight": (None, _BIG), "heading_weight": (None, _BIG),
    "speed_weight": (None, _BIG), "obstacle_weight": (None, _BIG),
    "moving_weight": (None, _BIG), "obstacle_range_m": (None, 100),
    "inflation_decay_m": (None, 100), "lookahead_m": (None, 100),
    "keep_weight": (None, _BIG), "keep_m": (None, 100), "keep_horizon_s": (None, 10),
    "goal_tolerance_m": (None, 100), "stall_steps": (None, 100_000),
    "stall_distance_m": (None, 100),
    # MPPI (mppi.py): one tick rolls out batch_size x time_steps steps
    "batch_size": (None, 10_000), "time_steps": (None, 200), "model_dt_s": (0.001, 1),
    "vx_std_mps": (None, 10), "vy_std_mps": (None, 10), "wz_std_radps": (None, 20),
    "temperature": (None, _BIG), "collision_cost": (None, _BIG),
    "obstacle_peak_weight": (None, _BIG), "inflation_radius_m": (None, 100),
    "cost_scaling_factor": (None, 1000), "path_align_weight": (None, _BIG),
    "path_follow_weight": (None, _BIG), "path_angle_weight": (None, _BIG),
    "goal_distance_m": (None, 1000), "disc_collision_cost": (None, _BIG),
    "disc_proximity_weight": (None, _BIG), "disc_decay_m": (None, 100),
    "smoothness_weight": (None, _BIG), "prefer_forward_weight": (None, _BIG),
    "slow_guide_speed_mps": (None, 100), "clearance_cell_m": (0.001, 1),
    "seed": (None, MAX_SEED), "replan_clearance_m": (None, 100),
}
"""Bounds of the parameters that the planner modules declare without an upper bound, by
field name: (lowest value or None to keep the declared one, highest value).

:class:`Checked` puts them into the field's :class:`~pathfuse.validate.ParamSpec` when a
parameter class is defined (a bound declared on the field itself wins), so they are
checked on construction, listed by ``pathfuse planners --params`` and sent to the forms of
``pathfuse serve``.  Every number a planner takes thus has an upper bound: values far past
any use (DWA with 250 x 250 samples over 20 s) are refused before a loop starts.
"""


def _bounded(spec: ParamSpec, name: str) -> ParamSpec | None:
    """``spec`` with the :data:`BOUNDS` of ``name`` (None when nothing changes)."""
    if spec.kind not in ("float", "int") or spec.le is not None or name not in BOUNDS:
        return None
    low, high = BOUNDS[name]
    if low is None:
        return dataclasses.replace(spec, le=high)
    return dataclasses.replace(spec, gt=None, ge=low, le=high)


@dataclass(frozen=True)
class Checked:
    """Base: checks every :func:`~pathfuse.validate.param` field on construction.

    A subclass's own numeric fields declared without an upper bound get the one of
    :data:`BOUNDS` (by field name) when the class is defined.
    """

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        for name, value in list(vars(cls).items()):
            if not isinstance(value, dataclasses.Field):
                continue
            spec = value.metadata.get("param")
            new = _bounded(spec, name) if isinstance(spec, ParamSpec) else None
            if new is not None:
                value.metadata = types.MappingProxyType({**value.metadata, "param": new})

    def __post_init__(self) -> None:
        check_fields(self)


GLOBAL_PLANNER_HELP = ("the global planner whose path the controller follows (a name of "
                       "'pathfuse planners': astar, jps, astar-smooth, thetastar, "
                       "lazy-thetastar, shortest, or a plug-in's)")


@dataclass(frozen=True)
class GlobalChoice(Checked):
    """The global planner a controller follows, by its registered name (the preset's own
    by default; any registered one, plug-ins' included)."""

    global_planner: str = param("astar", help=GLOBAL_PLANNER_HELP)

    def __post_init__(self) -> None:
        super().__post_init__()
        from pathfuse.planners.registry import get_global_planner

        get_global_planner(self.global_planner)  # names the choices when unknown


@dataclass(frozen=True)
class GlobalAStarParams(Checked):
    """The global A* of the A*-based planners."""

    heuristic: str = param("euclidean", choices=HEURISTICS,
                           help="A* heuristic: 'euclidean' (the paper's eq. 2) or 'octile' "
                                "(tighter on an 8-connected grid); both are exact")


@dataclass(frozen=True)
class FieldParams(Checked):
    """The potential field and the stepping of APF-style controllers (paper values)."""

    k_att: float = param(K_ATT, gt=0, le=1e6, help="attractive gain K_att (eq. 3, 5)")
    k_rep: float = param(K_REP, ge=0, le=1e6, help="repulsive gain K_rep (eq. 4, 6)")
    rho0_m: float = param(RHO0_M, gt=0, le=100, unit="m",
                          help="influence distance rho_0 of an obstacle point (eq. 4, 6)")
    step_m: float | None = param(
        None, gt=0, le=100, unit="m", optional=True,
        help="length of one move when planning offline (default: 0.1 cell; fusion 0.5 "
             "cell); online the move per tick is max_speed x dt")
    goal_tolerance_m: float | None = param(
        None, gt=0, le=100, unit="m", optional=True,
        help="within this distance a clear straight move onto the goal ends the run "
             "(default: one move)")
    stall_steps: int = param(40, ge=1, le=100_000, help="look-back of the stall test, in moves")
    stall_distance_m: float | None = param(
        None, gt=0, le=100, unit="m", optional=True,
        help="a net move below this over stall_steps moves is a stall (default: 2.5 moves)")
    safe_step: bool = param(True, help="a move that would hit an obstacle slides along it or "
                                       "shortens, so no move ever collides (ours); false = the "
                                       "paper: the full step along the force, and a step that "
                                       "touches an obstacle ends the run as COLLISION")
    stall_exit: bool = param(True, help="end the run (fusion: escape) when the net move over "
                                        "stall_steps moves is below stall_distance_m (ours); "
                                        "false = the paper's loop, which stops only at the goal "
                                        "or the move cap")
    static_repulsion: str = param(
        "cells", choices=("cells", "boundary"),
        help="the static map's repulsion: 'cells' = eq. 6 summed over every occupied cell "
             "centre within rho0_m (the paper; it grows as the cells shrink); 'boundary' = "
             "eq. 6 once, on the exact distance to the nearest occupied square plus "
             "boundary_offset_m (ours; the same at any resolution)")
    boundary_offset_m: float = param(
        BOUNDARY_OFFSET_M, gt=0, le=100, unit="m",
        help="added to the distance of the boundary repulsion (default: half the paper's "
             "1 m cell, so an isolated paper cell pushes as in the paper)")


@dataclass(frozen=True)
class DiscParams(Checked):
    """How sensed moving discs repel (online only; no effect on a static map)."""

    k_rep_moving: float | None = param(None, ge=0, le=1e6, optional=True,
                                       help="repulsive gain of a moving disc (default: k_rep)")
    rho0_moving_m: float | None = param(None, gt=0, le=100, unit="m", optional=True,
                                        help="influence distance of a moving disc, measured "
                                             "on the gap (default: rho0_m)")
    repulsion: str = param("position", choices=("position", "velocity"),
                           help="eq. 6 on the gap, or the velocity-aware form of Ge and Cui "
                                "(2002)")
    a_max: float = param(1.0, gt=0, le=100, unit="m/s^2",
                         help="braking deceleration of the velocity-aware repulsion")
    swerve: float = param(1.0, ge=0, le=100,
                          help="tangential share of a disc's repulsion, pushing the robot "
                               "past it (ours, not the paper's; 0 = off)")
    dodge: bool = param(True, help="when a disc pins the robot against a wall, take the clear "
                                   "move that most increases the gap (ours; false = off)")


@dataclass(frozen=True)
class PersonalSpaceParams(Checked):
    """Personal space among sensed moving discs (ours;
    :mod:`pathfuse.planners.controllers.social`)."""

    social: bool = param(True, help="social critics among sensed moving discs (ours): "
                                    "personal space over the predicted gaps (and, in dwa and "
                                    "the fusion, a committed passing side); false: off")
    social_weight: float = param(20.0, ge=0, le=1e6,
                                 help="personal-space critic: the shortfall of the least "
                                      "predicted gap to a disc against personal_m, relative, "
                                      "squared")
    personal_m: float = param(0.5, gt=0, le=10, unit="m",
                              help="personal space: the gap kept from moving discs where the "
                                   "space allows")
    dwell_s: float = param(0.0, ge=0, le=30, unit="s",
                           help="yield outside a walker's lane (ours): a rollout pays "
                                "dwell_weight where it ends within personal_m of the lane a "
                                "sensed disc (in mppi and the fusion only a steady one, that "
                                "kept its velocity for 1 s; in dwa every one unless "
                                "dwell_steady), predicted at constant velocity, "
                                "sweeps in the "
                                "dwell_s after the rollout (the spot where the robot may have "
                                "to stand); 0 = off")
    dwell_weight: float = param(50.0, ge=0, le=1e6,
                                help="weight of the dwell critic (dwell_s), times the "
                                     "shortfall against personal_m, relative, halved for a "
                                     "disc that reaches the spot only at the end of dwell_s")
    social_replan: bool = param(True, help="ours, with social: the A* path replanned around "
                                           "the sensed discs keeps personal_m more from them "
                                           "where the room allows (off, or social off: they "
                                           "are grown by the robot's radius only)")


@dataclass(frozen=True)
class SocialParams(PersonalSpaceParams):
    """Personal space and a committed passing side (ours), for ``dwa`` and the fusion's
    window."""

    side_weight: float = param(2.0, ge=0, le=1e6,
                               help="passing-side critic: the cost of passing a disc on the "
                                    "other side than committed")


_DD = " (diff-drive robot online; no effect on a holonomic robot)"


@dataclass(frozen=True)
class PursuitParams(Checked):
    """Regulated Pure Pursuit, the path followers' controller on a diff-drive robot
    (:mod:`pathfuse.planners.controllers.rpp`; Nav2's defaults unless the help says otherwise)."""

    lookahead_time_s: float = param(
        1.5, gt=0, le=60, unit="s",
        help="lookahead = |v| x this, clipped to [min_lookahead_m, max_lookahead_m] "
             "(Nav2's lookahead_time)" + _DD)
    min_lookahead_m: float = param(0.3, gt=0, le=100, unit="m",
                                   help="shortest lookahead (Nav2's min_lookahead_dist)" + _DD)
    max_lookahead_m: float = param(0.9, gt=0, le=100, unit="m",
                                   help="longest lookahead (Nav2's max_lookahead_dist)" + _DD)
    rotate_to_heading_min_angle_rad: float = param(
        0.785, gt=0, le=3.1416, unit="rad",
        help="beyond this bearing of the carrot the robot brakes and turns on the spot "
             "(Nav2's rotate_to_heading_min_angle)" + _DD)
    regulated_min_radius_m: float = param(
        0.9, ge=0, le=100, unit="m",
        help="on a pursuit arc of smaller radius the speed scales by radius / this "
             "(Nav2's regulated_linear_scaling_min_radius; 0 = off)" + _DD)
    regulated_min_speed_mps: float = param(
        0.25, ge=0, le=100, unit="m/s",
        help="the curvature and proximity heuristics never slow the robot below this "
             "(Nav2's regulated_linear_scaling_min_speed)" + _DD)
    proximity_distance_m: float = param(
        0.1, ge=0, le=100, unit="m",
        help="closer than this to an obstacle (the exact gap between the robot disc and the "
             "map) the speed scales by gap / this (0 = off); Nav2's cost_scaling_dist, 0.3 m "
             "from the robot's centre with gain 1, is a gap of 0.1 m for pathfuse's default "
             "0.2 m robot" + _DD)
    approach_distance_m: float = param(
        0.6, ge=0, le=100, unit="m",
        help="within this remaining distance to the goal the speed scales by distance / this "
             "(Nav2's approach_velocity_scaling_dist; 0 = off); the robot also never goes "
             "faster than it can brake to the goal" + _DD)
    min_approach_speed_mps: float = param(
        0.05, gt=0, le=100, unit="m/s",
        help="the approach scaling keeps at least this speed (Nav2's "
             "min_approach_linear_velocity)" + _DD)
    pose_search_distance_m: float = param(
        1.5, gt=0, le=1000, unit="m",
        help="the closest path point is searched this far along the path ahead of the "
             "last one, so progress never jumps back nor across a loop (Nav2's "
             "max_robot_pose_search_dist, half its default 3 m local costmap)" + _DD)
    clear_carrot: bool = param(
        True, help="shorten the lookahead until the disc swept along the arc to the carrot "
                   "keeps the robot's radius from the map (ours; Nav2's collision check "
                   "instead stops the robot, and its paths keep away from walls by the "
                   "costmap's inflation, which pathfuse's shortest paths do not)" + _DD)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.max_lookahead_m < self.min_lookahead_m:
            raise ConfigError(f"max_lookahead_m: must be >= min_lookahead_m "
                              f"({self.min_lookahead_m:g}), got {self.max_lookahead_m!r}")
