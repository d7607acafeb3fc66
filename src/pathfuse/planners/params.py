"""The parameter groups the planners share, declared once with their defaults.

Every planner's parameters are one frozen dataclass built from these
groups; each field carries its constraint, unit and help text
(:func:`pathfuse.validate.param`), which ``pathfuse planners`` prints and
:func:`pathfuse.validate.check_fields` enforces.  Offline (``plan()``) and
online (``simulate()``) use the same instance and the same defaults.
"""

from __future__ import annotations

from dataclasses import dataclass

from pathfuse.field.forces import K_ATT, K_REP, RHO0_M
from pathfuse.field.repulsion import BOUNDARY_OFFSET_M
from pathfuse.search.astar import HEURISTICS
from pathfuse.validate import check_fields, param

__all__ = ["Checked", "GlobalAStarParams", "FieldParams", "DiscParams"]


@dataclass(frozen=True)
class Checked:
    """Base: checks every :func:`~pathfuse.validate.param` field on construction."""

    def __post_init__(self) -> None:
        check_fields(self)


@dataclass(frozen=True)
class GlobalAStarParams(Checked):
    """The global A* of the A*-based planners."""

    heuristic: str = param("euclidean", choices=HEURISTICS,
                           help="A* heuristic: 'euclidean' (the paper's eq. 2) or 'octile' "
                                "(tighter on an 8-connected grid); both are exact")


@dataclass(frozen=True)
class FieldParams(Checked):
    """The potential field and the stepping of APF-style controllers (paper values)."""

    k_att: float = param(K_ATT, gt=0, help="attractive gain K_att (eq. 3, 5)")
    k_rep: float = param(K_REP, ge=0, help="repulsive gain K_rep (eq. 4, 6)")
    rho0_m: float = param(RHO0_M, gt=0, unit="m",
                          help="influence distance rho_0 of an obstacle point (eq. 4, 6)")
    step_m: float | None = param(
        None, gt=0, unit="m", optional=True,
        help="length of one move when planning offline (default: 0.1 cell; fusion 0.5 "
             "cell); online the move per tick is max_speed x dt")
    goal_tolerance_m: float | None = param(
        None, gt=0, unit="m", optional=True,
        help="within this distance a clear straight move onto the goal ends the run "
             "(default: one move)")
    stall_steps: int = param(40, ge=1, help="look-back of the stall test, in moves")
    stall_distance_m: float | None = param(
        None, gt=0, unit="m", optional=True,
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
        BOUNDARY_OFFSET_M, gt=0, unit="m",
        help="added to the distance of the boundary repulsion (default: half the paper's "
             "1 m cell, so an isolated paper cell pushes as in the paper)")


@dataclass(frozen=True)
class DiscParams(Checked):
    """How sensed moving discs repel (online only; no effect on a static map)."""

    k_rep_moving: float | None = param(None, ge=0, optional=True,
                                       help="repulsive gain of a moving disc (default: k_rep)")
    rho0_moving_m: float | None = param(None, gt=0, unit="m", optional=True,
                                        help="influence distance of a moving disc, measured "
                                             "on the gap (default: rho0_m)")
    repulsion: str = param("position", choices=("position", "velocity"),
                           help="eq. 6 on the gap, or the velocity-aware form of Ge and Cui "
                                "(2002)")
    a_max: float = param(1.0, gt=0, unit="m/s^2",
                         help="braking deceleration of the velocity-aware repulsion")
    swerve: float = param(1.0, ge=0,
                          help="tangential share of a disc's repulsion, pushing the robot "
                               "past it (ours, not the paper's; 0 = off)")
    dodge: bool = param(True, help="when a disc pins the robot against a wall, take the clear "
                                   "move that most increases the gap (ours; false = off)")
