"""The settings arrays of the stepping loops of :mod:`pathfuse.field.kernels`.

:func:`pack_field` and :func:`pack_fusion` fill the float and int arrays ``f``
and ``i`` (their slots are the ``F_*`` and ``I_*`` constants of the kernels'
module); :func:`disc_settings` bundles the moving-disc settings both take.
"""

from __future__ import annotations

import numpy as np

from pathfuse.field.kernels import (
    F_AMAX,
    F_BACKOFF,
    F_CLEAR,
    F_GX,
    F_GY,
    F_KATT,
    F_KMOV,
    F_KREP,
    F_MARGIN,
    F_NEXP,
    F_OFFSET,
    F_OX,
    F_OY,
    F_R1,
    F_R2,
    F_RADIUS,
    F_REACH,
    F_RES,
    F_RHO0,
    F_RHOMOV,
    F_SCALE,
    F_STALLD,
    F_STEP,
    F_SUBTOL,
    F_SWERVE,
    F_TOL,
    I_AHEAD,
    I_BOUNDARY,
    I_DRIVE,
    I_ESC_PTS,
    I_ESCAPE,
    I_IMPROVED,
    I_SAFE,
    I_STALL,
    I_STALLN,
    I_TOGOAL,
    I_VELAWARE,
    N_F,
    N_I,
)

__all__ = ["disc_settings", "pack_field", "pack_fusion"]


def pack_field(goal, k_att, k_rep, rho0_m, step_m, tol_m, clear_m, stall_steps,
               stall_distance_m, ox, oy, res, subgoal_tol_m, improved, to_goal, rep_exponent,
               rep_scale_m, discs, safe_step=True, stall_exit=True, margin_m=0.0,
               boundary=False, offset_m=0.5):
    """Float and int settings of :func:`field_loop`; ``discs`` is :func:`disc_settings`."""
    f = np.zeros(N_F)
    f[F_GX], f[F_GY] = float(goal[0]), float(goal[1])
    f[F_KATT], f[F_KREP], f[F_RHO0] = k_att, k_rep, rho0_m
    f[F_STEP], f[F_TOL], f[F_CLEAR], f[F_STALLD] = step_m, tol_m, clear_m, stall_distance_m
    f[F_OX], f[F_OY], f[F_RES] = ox, oy, res
    f[F_SUBTOL], f[F_NEXP], f[F_SCALE] = subgoal_tol_m, rep_exponent, rep_scale_m
    f[F_MARGIN] = margin_m
    f[F_OFFSET] = offset_m
    i = np.zeros(N_I, dtype=np.int64)
    i[I_STALLN] = stall_steps
    i[I_IMPROVED] = 1 if improved else 0
    i[I_TOGOAL] = 1 if to_goal else 0
    i[I_SAFE] = 1 if safe_step else 0
    i[I_STALL] = 1 if stall_exit else 0
    i[I_BOUNDARY] = 1 if boundary else 0
    _put_discs(f, i, discs)
    return f, i


def disc_settings(robot_radius_m, k_rep_moving, rho0_moving_m, reach_m, velocity_aware, a_max,
                  swerve):
    """The moving-disc settings of both loops, as a tuple for :func:`pack_field`."""
    return (robot_radius_m, k_rep_moving, rho0_moving_m, reach_m, velocity_aware, a_max, swerve)


def _put_discs(f, i, discs):
    r, k, rho, reach, va, a_max, swerve = discs
    f[F_RADIUS], f[F_KMOV], f[F_RHOMOV], f[F_REACH] = r, k, rho, reach
    f[F_AMAX], f[F_SWERVE] = a_max, swerve
    i[I_VELAWARE] = 1 if va else 0


def pack_fusion(goal, k_att, k_rep, rho0_m, r1_m, r2_m, step_m, tol_m, clear_m, stall_steps,
                stall_distance_m, ox, oy, res, ahead, escape, escape_points, backoff_window_m,
                drive, discs, safe_step=True, stall_exit=True, margin_m=0.0, boundary=False,
                offset_m=0.5):
    """Float and int settings of :func:`fusion_loop` (``r2_m`` is the repulsion radius)."""
    f = np.zeros(N_F)
    f[F_GX], f[F_GY] = float(goal[0]), float(goal[1])
    f[F_KATT], f[F_KREP], f[F_RHO0] = k_att, k_rep, rho0_m
    f[F_STEP], f[F_TOL], f[F_CLEAR], f[F_STALLD] = step_m, tol_m, clear_m, stall_distance_m
    f[F_OX], f[F_OY], f[F_RES] = ox, oy, res
    f[F_R1], f[F_R2], f[F_BACKOFF] = r1_m, r2_m, backoff_window_m
    f[F_MARGIN] = margin_m
    f[F_OFFSET] = offset_m
    i = np.zeros(N_I, dtype=np.int64)
    i[I_STALLN] = stall_steps
    i[I_AHEAD] = ahead
    i[I_ESCAPE] = 1 if escape else 0
    i[I_ESC_PTS] = escape_points
    i[I_DRIVE] = 1 if drive else 0
    i[I_SAFE] = 1 if safe_step else 0
    i[I_STALL] = 1 if stall_exit else 0
    i[I_BOUNDARY] = 1 if boundary else 0
    _put_discs(f, i, discs)
    return f, i
