"""The named settings of the stepping loops of :mod:`pathfuse.field.kernels`.

Each is a :class:`typing.NamedTuple` of floats, ints and bools with the unit
in each name where there is one: numba kernels take it as **one argument**,
read its fields by name and cache their machine code on disk (as
:class:`~pathfuse.planners.controllers.dwa_kernel.DwaSettings` and
:class:`~pathfuse.costmap.Costmap`).  :func:`pack_field` builds the
:class:`FieldSettings` of :func:`~pathfuse.field.kernels.field_loop`,
:func:`pack_fusion` the :class:`FusionSettings` of
:func:`~pathfuse.field.kernels.fusion_loop`, and :func:`disc_settings` the
:class:`DiscSettings` (the moving discs' repulsion) both loops take.  The map,
its frame, the robot's radius and the clearance it keeps are not settings:
they are the :class:`~pathfuse.costmap.Costmap` the loops take.

Examples
--------
>>> s = pack_fusion((11.0, 11.0), 40.0, 20.0, 2.0, 1.5, 2.0, 0.5, 0.5, 3, 1.25, 0, True,
...                 3, 8.0, False)
>>> s.r1_m, s.r2_m, s.stall_steps, s.escape_points, s.safe_step
(1.5, 2.0, 3, 3, True)
>>> d = disc_settings(20.0, 2.0, 2.0, False, 1.0, 1.0)
>>> d.reach_m, d.robot_vx_mps
(2.0, 0.0)
"""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["DiscSettings", "FieldSettings", "FusionSettings", "disc_settings", "pack_field",
           "pack_fusion"]


class FieldSettings(NamedTuple):
    """The settings of :func:`~pathfuse.field.kernels.field_loop` (APF, ref6, ref7), read by
    name; from :func:`pack_field`."""

    goal_x_m: float
    goal_y_m: float
    k_att: float
    """K_att of eq. 5."""
    k_rep: float
    """K_rep of eq. 6 (the static map)."""
    rho0_m: float
    """rho_0 of eq. 6: the static map's repulsion range."""
    step_m: float
    """The length of one move."""
    goal_tolerance_m: float
    stall_steps: int
    """The stall window, in moves."""
    stall_distance_m: float
    """A net move below this over the stall window is a stall."""
    safe_step: bool
    """The safe step (ours) instead of the paper's full step along the force."""
    stall_exit: bool
    """The stall test (ours; the paper's loop ends only at the goal)."""
    boundary: bool
    """The boundary repulsion (ours) instead of the paper's per-cell sum."""
    boundary_offset_m: float
    """The offset of the boundary repulsion."""
    margin_m: float
    """The soft safety margin beyond the radius (ours; 0 = off)."""
    subgoal_tolerance_m: float
    """A sub-goal is passed within this distance."""
    improved: bool
    """The Ge-Cui repulsion (ref6) instead of eq. 6."""
    rep_to_goal: bool
    """Ge-Cui: scaled by the distance to the goal instead of to the sub-goal."""
    rep_exponent: float
    """n of the Ge-Cui repulsion."""
    rep_scale_m: float
    """L of the Ge-Cui repulsion."""


class FusionSettings(NamedTuple):
    """The settings of :func:`~pathfuse.field.kernels.fusion_loop` (Algorithm 2 and the
    escape), read by name; from :func:`pack_fusion`."""

    goal_x_m: float
    goal_y_m: float
    k_att: float
    """K_att of eq. 5 (the goal and each attracting path point)."""
    k_rep: float
    """K_rep of eq. 6 (the static map)."""
    rho0_m: float
    """rho_0 of eq. 6."""
    step_m: float
    """The length of one move."""
    goal_tolerance_m: float
    stall_steps: int
    """The stall window, in moves."""
    stall_distance_m: float
    """A net move below this over the stall window is a stall."""
    safe_step: bool
    """The safe step (ours) instead of the paper's full step along the force."""
    stall_exit: bool
    """The stall test (ours)."""
    boundary: bool
    """The boundary repulsion (ours) instead of the paper's per-cell sum."""
    boundary_offset_m: float
    """The offset of the boundary repulsion."""
    margin_m: float
    """The soft safety margin beyond the radius (ours; 0 = off)."""
    r1_m: float
    """The path points within this distance attract (eq. 7)."""
    r2_m: float
    """The occupied cells within this distance repel."""
    ahead: int
    """Which path points count as ahead (``AHEAD_*`` of :mod:`pathfuse.field.repulsion`)."""
    escape: bool
    """The local-minimum escape along the path (ours)."""
    escape_points: int
    """Path points to follow in an escape before Algorithm 2 resumes."""
    backoff_window_m: float
    """How far back along the walk an escape looks for its rejoin point."""
    drive: bool
    """Online: an escape drives back along the walk instead of dropping it."""


class DiscSettings(NamedTuple):
    """The moving discs' repulsion of both loops
    (:func:`~pathfuse.field.repulsion.disc_repulsion`), read by name; from
    :func:`disc_settings`.  No effect without sensed discs."""

    k_rep: float
    """K_rep of the discs."""
    rho0_m: float
    """rho_0 of the discs."""
    reach_m: float
    """Only discs whose gap is below ``min(reach_m, rho0_m)`` repel."""
    velocity_aware: bool
    """The velocity form (Ge and Cui) instead of eq. 6 on the gap."""
    a_max_mps2: float
    """The braking deceleration of the velocity form."""
    swerve: float
    """The tangential push, times the radial one (ours; 0 = off)."""
    robot_vx_mps: float
    """The robot's velocity as last observed (online: replaced every tick)."""
    robot_vy_mps: float


def pack_field(goal, k_att, k_rep, rho0_m, step_m, tol_m, stall_steps, stall_distance_m,
               subgoal_tol_m, improved, to_goal, rep_exponent, rep_scale_m, safe_step=True,
               stall_exit=True, margin_m=0.0, boundary=False, offset_m=0.5) -> FieldSettings:
    """The :class:`FieldSettings` of :func:`~pathfuse.field.kernels.field_loop`.

    Examples
    --------
    >>> s = pack_field((11, 11), 40, 20, 2, 0.1, 0.1, 3, 0.25, 0.5, True, False, 2, 2.0)
    >>> s.goal_x_m, s.subgoal_tolerance_m, s.stall_steps, s.improved, s.rep_exponent
    (11.0, 0.5, 3, True, 2.0)
    """
    return FieldSettings(
        goal_x_m=float(goal[0]), goal_y_m=float(goal[1]), k_att=float(k_att),
        k_rep=float(k_rep), rho0_m=float(rho0_m), step_m=float(step_m),
        goal_tolerance_m=float(tol_m), stall_steps=int(stall_steps),
        stall_distance_m=float(stall_distance_m), safe_step=bool(safe_step),
        stall_exit=bool(stall_exit), boundary=bool(boundary),
        boundary_offset_m=float(offset_m), margin_m=float(margin_m),
        subgoal_tolerance_m=float(subgoal_tol_m), improved=bool(improved),
        rep_to_goal=bool(to_goal), rep_exponent=float(rep_exponent),
        rep_scale_m=float(rep_scale_m))


def pack_fusion(goal, k_att, k_rep, rho0_m, r1_m, r2_m, step_m, tol_m, stall_steps,
                stall_distance_m, ahead, escape, escape_points, backoff_window_m, drive,
                safe_step=True, stall_exit=True, margin_m=0.0, boundary=False,
                offset_m=0.5) -> FusionSettings:
    """The :class:`FusionSettings` of :func:`~pathfuse.field.kernels.fusion_loop` (``r2_m``
    is the repulsion radius)."""
    return FusionSettings(
        goal_x_m=float(goal[0]), goal_y_m=float(goal[1]), k_att=float(k_att),
        k_rep=float(k_rep), rho0_m=float(rho0_m), step_m=float(step_m),
        goal_tolerance_m=float(tol_m), stall_steps=int(stall_steps),
        stall_distance_m=float(stall_distance_m), safe_step=bool(safe_step),
        stall_exit=bool(stall_exit), boundary=bool(boundary),
        boundary_offset_m=float(offset_m), margin_m=float(margin_m), r1_m=float(r1_m),
        r2_m=float(r2_m), ahead=int(ahead), escape=bool(escape),
        escape_points=int(escape_points), backoff_window_m=float(backoff_window_m),
        drive=bool(drive))


def disc_settings(k_rep_moving, rho0_moving_m, reach_m, velocity_aware, a_max,
                  swerve) -> DiscSettings:
    """The :class:`DiscSettings` of both loops (the robot's velocity zero until observed)."""
    return DiscSettings(k_rep=float(k_rep_moving), rho0_m=float(rho0_moving_m),
                        reach_m=float(reach_m), velocity_aware=bool(velocity_aware),
                        a_max_mps2=float(a_max), swerve=float(swerve), robot_vx_mps=0.0,
                        robot_vy_mps=0.0)
