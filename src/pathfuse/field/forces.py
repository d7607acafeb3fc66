"""Artificial potential field: the potentials and forces of the paper, eq. 3-6.

Two forms of each formula live here, and a test keeps them equal:

* vectorised NumPy functions for users and tests (:func:`attractive_potential`,
  :func:`attractive_force`, :func:`repulsive_potential`,
  :func:`repulsive_force`), which broadcast over points and obstacles;
* scalar ``@njit`` kernels (:func:`att_force_xy`, :func:`rep_force_xy`) that the
  stepping loops of :mod:`pathfuse.field.stepper` call once per obstacle.

Formulas (``X`` robot, ``X_g`` goal, ``X_o`` obstacle, ``d = |X - X_o|``)::

    U_att(X) = 1/2 K_att |X - X_g|^2                          (eq. 3)
    F_att(X) = -K_att (X - X_g)                               (eq. 5, vector form)
    U_rep(X) = 1/2 K_rep (1/d - 1/rho_0)^2   if d <= rho_0    (eq. 4)
             = 0                             otherwise
    F_rep(X) = K_rep (1/d - 1/rho_0) / d^2 * (X - X_o) / d    (eq. 6, = -grad U_rep)

Eq. 6 as printed gives the magnitude; the direction is away from the
obstacle, which makes it the negative gradient of eq. 4 (checked numerically in
``tests/test_forces.py``).

Finiteness: every function returns finite values for finite inputs of
ordinary size (|coordinates| below about 1e150).  A robot *at* an obstacle
point (``d == 0``) gets a zero repulsion (the direction is undefined), and
distances below :data:`D_MIN_M` are clamped to it in the magnitude, so a robot
arbitrarily close to an obstacle point gets a large but finite push.  A robot
at the goal gets a zero attraction.

Examples
--------
>>> import numpy as np
>>> attractive_force([1.0, 1.0], [11.0, 11.0], k_att=40.0).tolist()
[400.0, 400.0]
>>> f = repulsive_force([1.0, 0.0], [0.0, 0.0], k_rep=5.0, rho0_m=2.0)
>>> f.tolist()  # 5 * (1/1 - 1/2) / 1**2 = 2.5, pointing away from the obstacle
[2.5, 0.0]
>>> repulsive_force([3.0, 0.0], [0.0, 0.0], k_rep=5.0, rho0_m=2.0).tolist()
[0.0, 0.0]
>>> repulsive_force([0.0, 0.0], [0.0, 0.0], 5.0, 2.0).tolist()  # at the obstacle: finite
[0.0, 0.0]
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = [
    "K_ATT",
    "K_REP",
    "RHO0_M",
    "D_MIN_M",
    "attractive_potential",
    "attractive_force",
    "repulsive_potential",
    "repulsive_force",
    "total_force",
    "att_force_xy",
    "rep_force_xy",
    "rep_potential_d",
]

#: Paper defaults (Section IV.A).
K_ATT = 40.0
K_REP = 5.0
RHO0_M = 2.0
#: Distances (m) below this are clamped in the repulsion magnitude, keeping it finite.
D_MIN_M = 1e-9


def _xy(a: object) -> np.ndarray:
    return np.asarray(a, dtype=np.float64)


# --------------------------------------------------------------------- numpy (vectorised)
def attractive_potential(x: object, goal: object, k_att: float = K_ATT) -> np.ndarray:
    """Eq. 3: ``1/2 K_att |X - X_g|^2`` for points ``x`` of shape (..., 2).

    >>> float(attractive_potential([3.0, 4.0], [0.0, 0.0], k_att=2.0))
    25.0
    """
    d = _xy(x) - _xy(goal)
    return 0.5 * k_att * np.sum(d * d, axis=-1)


def attractive_force(x: object, goal: object, k_att: float = K_ATT) -> np.ndarray:
    """Eq. 5 (vector form): ``-K_att (X - X_g)``, shape (..., 2).

    >>> attractive_force([3.0, 4.0], [0.0, 0.0], k_att=2.0).tolist()
    [-6.0, -8.0]
    """
    return -k_att * (_xy(x) - _xy(goal))


def repulsive_potential(
    x: object, obstacle: object, k_rep: float = K_REP, rho0_m: float = RHO0_M
) -> np.ndarray:
    """Eq. 4: ``1/2 K_rep (1/d - 1/rho_0)^2`` within ``rho_0``, else 0.

    ``d`` below :data:`D_MIN_M` is clamped (the potential stays finite).

    >>> float(repulsive_potential([1.0, 0.0], [0.0, 0.0], k_rep=5.0, rho0_m=2.0))
    0.625
    """
    diff = _xy(x) - _xy(obstacle)
    d = np.hypot(diff[..., 0], diff[..., 1])
    dc = np.maximum(d, D_MIN_M)
    u = 0.5 * k_rep * (1.0 / dc - 1.0 / rho0_m) ** 2
    return np.where(d <= rho0_m, u, 0.0)


def repulsive_force(
    x: object, obstacle: object, k_rep: float = K_REP, rho0_m: float = RHO0_M
) -> np.ndarray:
    """Eq. 6: ``K_rep (1/d - 1/rho_0) / d^2`` along ``(X - X_o)/d`` within ``rho_0``.

    Broadcasts ``x`` (..., 2) against ``obstacle`` (..., 2).  Zero beyond
    ``rho_0`` and at ``d == 0``; finite everywhere.

    >>> repulsive_force([0.0, 0.5], [0.0, 0.0], k_rep=5.0, rho0_m=2.0).tolist()
    [0.0, 30.0]
    """
    diff = _xy(x) - _xy(obstacle)
    d = np.hypot(diff[..., 0], diff[..., 1])
    dc = np.maximum(d, D_MIN_M)
    mag = k_rep * (1.0 / dc - 1.0 / rho0_m) / (dc * dc)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = np.where(d[..., None] > 0, diff / np.where(d > 0, d, 1.0)[..., None], 0.0)
    mag = np.where((d <= rho0_m) & (d > 0), mag, 0.0)
    return mag[..., None] * unit


def total_force(
    x: object,
    goal: object,
    obstacles: object,
    k_att: float = K_ATT,
    k_rep: float = K_REP,
    rho0_m: float = RHO0_M,
) -> np.ndarray:
    """Goal attraction plus the repulsion of *every* obstacle point (a brute-force reference).

    ``x`` and ``goal`` are (2,), ``obstacles`` (K, 2).  The stepping kernels
    compute the same sum from a local window of the grid; this function is the
    slow, obvious version used to check them.

    >>> total_force([1.0, 0.0], [1.0, 5.0], [[0.0, 0.0]], k_att=1.0).tolist()
    [2.5, 5.0]
    """
    f = attractive_force(x, goal, k_att)
    obs = _xy(obstacles).reshape(-1, 2)
    if obs.shape[0]:
        f = f + repulsive_force(_xy(x)[None, :], obs, k_rep, rho0_m).sum(axis=0)
    return f


# --------------------------------------------------------------------- numba (scalar)
@njit(cache=True, inline="always")
def att_force_xy(x: float, y: float, px: float, py: float, k_att: float) -> tuple[float, float]:
    """Scalar eq. 5: attraction of point ``(px, py)`` on a robot at ``(x, y)``."""
    return -k_att * (x - px), -k_att * (y - py)


@njit(cache=True, inline="always")
def rep_force_xy(dx: float, dy: float, k_rep: float, rho0_m: float) -> tuple[float, float]:
    """Scalar eq. 6 for the offset ``(dx, dy) = X - X_o`` of the robot from one obstacle point."""
    d = math.hypot(dx, dy)
    if d > rho0_m or d == 0.0:
        return 0.0, 0.0
    dc = d if d > D_MIN_M else D_MIN_M
    m = k_rep * (1.0 / dc - 1.0 / rho0_m) / (dc * dc)
    return m * (dx / d), m * (dy / d)


@njit(cache=True, inline="always")
def rep_potential_d(d: float, k_rep: float, rho0_m: float) -> float:
    """Scalar eq. 4 as a function of the distance ``d``."""
    if d > rho0_m:
        return 0.0
    dc = d if d > D_MIN_M else D_MIN_M
    t = 1.0 / dc - 1.0 / rho0_m
    return 0.5 * k_rep * t * t
