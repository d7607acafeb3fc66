"""Social behaviour among moving discs (people), shared by ``dwa``, the fusion's window and
``mppi`` (ours; after the proxemics and passing conventions of social navigation).

Two critics of the sampled rollouts (in :mod:`pathfuse.planners.controllers.dwa_kernel` and
:mod:`pathfuse.planners.controllers.mppi_kernel`), on by default whenever a moving disc is sensed:

* **personal space**: each sensed disc is predicted at constant velocity over
  the rollout's horizon; a rollout whose least predicted gap to a disc falls
  below ``personal_m`` pays ``social_weight * (shortfall / personal_m)**2``
  (the worst disc counts).  The gap is the predicted one, over time, not the
  present distance, so a disc walking away costs nothing and one about to
  cross the robot's route costs before it is near (the velocity-obstacle
  view: repulsion by time to collision rather than by distance);
* **passing side** (hysteresis): the side on which a disc is passed is the
  side of the route it lies on at the rollout's closest approach.  The first
  tick the chosen command comes within ``personal_m + commit_m`` of a disc,
  :class:`PassingSides` commits to that side; from then on a rollout passing
  the disc on the other side pays ``side_weight``, until the disc is behind
  the robot or no longer sensed.  The robot picks a side once instead of
  swinging between two people or in front of one.

A third critic, **dwell** (``dwell_s``, on by default in the fusion among discs, off in
``dwa`` and ``mppi``): a rollout ends where the robot may have to stand.  Each sensed
disc, predicted at constant velocity, sweeps a lane in the ``dwell_s`` after the
rollout's end; a rollout ending within ``personal_m`` of that lane pays
``dwell_weight`` times the shortfall (relative, halved for a disc that arrives only at
the end of ``dwell_s``): :func:`dwell_shortfall`.  The robot then waits outside a
walker's lane, not in it (a walker that does not react walks into a robot standing in
its way).

``social: false`` (a parameter of ``dwa``, ``fusion`` and ``mppi``) turns all three off.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

__all__ = ["PassingSides", "disc_ids", "dwell_shortfall", "COMMIT_M", "BEHIND_M"]

COMMIT_M = 1.0
"""A disc whose predicted gap to the chosen command's rollout is below ``personal_m``
plus this is an encounter: its passing side is committed."""
BEHIND_M = 0.3
"""A committed disc this far behind the robot (along the route, beyond both radii) is
released."""


class PassingSides:
    """The committed passing side of each sensed disc (see the module docstring).

    Examples
    --------
    >>> ps = PassingSides(personal_m=0.5)
    >>> ids = np.array([4])
    >>> ps.sides(ids).tolist()                    # nothing committed yet
    [0.0]
    >>> ps.update(ids, np.array([[1.0, 0.8]]), np.array([[3.0, 1.0]]), (0.0, 0.0), (1.0, 0.0),
    ...           np.array([0.3]), 0.2)           # chosen rollout passes it on the left
    >>> ps.sides(ids).tolist()
    [1.0]
    >>> ps.update(ids, np.array([[-1.0, 0.8]]), np.array([[-1.0, 1.0]]), (0.0, 0.0),
    ...           (1.0, 0.0), np.array([0.3]), 0.2)   # now behind the robot: released
    >>> ps.sides(ids).tolist()
    [0.0]
    """

    def __init__(self, personal_m: float) -> None:
        self.personal_m = float(personal_m)
        self.committed: dict[int, float] = {}
        self.commits = 0

    def sides(self, ids: np.ndarray) -> np.ndarray:
        """The committed side (+1 left of the route, -1 right, 0 none) of each sensed disc."""
        return np.array([self.committed.get(int(i), 0.0) for i in ids], dtype=np.float64)

    def update(self, ids: np.ndarray, chosen: np.ndarray, dpos: np.ndarray,
               position: Any, tangent: Any, drad: np.ndarray, radius: float) -> None:
        """After a tick: ``chosen[j] = (side, predicted gap)`` of the chosen command's
        rollout against sensed disc ``j``; ``tangent`` the route's direction at the robot."""
        keep: dict[int, float] = {}
        tx, ty = float(tangent[0]), float(tangent[1])
        for j, i in enumerate(ids):
            key = int(i)
            ahead = (float(dpos[j, 0]) - float(position[0])) * tx \
                + (float(dpos[j, 1]) - float(position[1])) * ty
            if ahead < -(float(drad[j]) + radius + BEHIND_M):
                continue  # passed: released
            side = self.committed.get(key, 0.0)
            if side == 0.0 and chosen[j, 0] != 0.0 \
                    and chosen[j, 1] < self.personal_m + COMMIT_M:
                side = float(chosen[j, 0])
                self.commits += 1
            if side != 0.0:
                keep[key] = side
        self.committed = keep


def disc_ids(obs: Any, n: int) -> np.ndarray:
    """The sensed discs' identities (their indices in the scenario), or ``0..n-1`` when the
    observation carries none."""
    ids = getattr(obs.obstacles, "ids", None)
    if ids is None or len(ids) != n:
        return np.arange(n)
    return np.asarray(ids)


@njit(cache=True)
def dwell_shortfall(px, py, t, dpos, dvel, drad, radius, dwell_s, personal_m):
    """The dwell critic of a rollout ending at ``(px, py)`` at time ``t`` (see the module
    docstring): over the sensed discs, the largest ``(personal_m - gap) / personal_m``
    (gap clipped at 0) times ``1 - u / 2``, where ``gap`` is the least distance between
    the robot's disc standing there and disc ``i`` moving on from ``dpos[i] + dvel[i] t``
    at ``dvel[i]`` for ``dwell_s``, and ``u`` in [0, 1] is when in ``dwell_s`` it comes
    closest.  0 when no disc comes within ``personal_m``.

    Examples
    --------
    >>> z = np.zeros((1, 2))
    >>> v = np.array([[0.0, 1.0]])               # a disc walking along +y at x = 3
    >>> r = np.array([0.25])
    >>> p = np.array([[3.0, -1.0]])
    >>> round(dwell_shortfall(3.0, 0.0, 0.0, p, v, r, 0.25, 1.5, 0.5), 3)   # in its lane
    0.667
    >>> dwell_shortfall(1.5, 0.0, 0.0, p, v, r, 0.25, 1.5, 0.5)   # 1.5 m beside it
    0.0
    >>> dwell_shortfall(3.0, 0.0, 0.0, p, z, r, 0.25, 1.5, 0.5)   # standing 1 m away
    0.0
    """
    worst = 0.0
    for i in range(drad.shape[0]):
        ax = dpos[i, 0] + dvel[i, 0] * t
        ay = dpos[i, 1] + dvel[i, 1] * t
        bx = dvel[i, 0] * dwell_s
        by = dvel[i, 1] * dwell_s
        l2 = bx * bx + by * by
        u = 0.0
        if l2 > 0.0:
            u = min(1.0, max(0.0, ((px - ax) * bx + (py - ay) * by) / l2))
        g = math.hypot(px - ax - u * bx, py - ay - u * by) - radius - drad[i]
        if g < personal_m:
            sh = (personal_m - max(g, 0.0)) / personal_m * (1.0 - 0.5 * u)
            if sh > worst:
                worst = sh
    return worst
