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

A third critic, **dwell** (``dwell_s``, on by default in the fusion among discs and in
``dwa``, off in ``mppi``): a rollout ends where the robot may have to stand.  Each sensed
disc, predicted at constant velocity, sweeps a lane in the ``dwell_s`` after the
rollout's end; a rollout ending within ``personal_m`` of that lane pays
``dwell_weight`` times the shortfall (relative, halved for a disc that arrives only at
the end of ``dwell_s``): :func:`dwell_shortfall`.  The robot then waits outside a
walker's lane, not in it (a walker that does not react walks into a robot standing in
its way).

``dwa``, ``mppi`` and the fusion replan their global path among discs keeping
``personal_m`` more from them where the room allows (ours, ``social_replan``), and ``dwa``
commits a disc's passing side as that path passes it (ours, ``path_sides``:
:func:`path_sides`), so the discs of a group get one side.

``social: false`` (a parameter of ``dwa``, ``fusion`` and ``mppi``) turns all of them off.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

__all__ = ["PassingSides", "SteadyDiscs", "disc_ids", "dwell_shortfall", "path_sides",
           "COMMIT_M", "BEHIND_M", "STEADY_S", "EVERY_DISC"]

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
               position: Any, tangent: Any, drad: np.ndarray, radius: float,
               prefer: np.ndarray | None = None) -> None:
        """After a tick: ``chosen[j] = (side, predicted gap)`` of the chosen command's
        rollout against sensed disc ``j``; ``tangent`` the route's direction at the robot.
        ``prefer[j]``, when given and not 0, is the side committed instead of the chosen
        rollout's (ours, ``dwa``'s ``path_sides``: the side the global path passes it on,
        :func:`path_sides`)."""
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
                if prefer is not None and prefer[j] != 0.0:
                    side = float(prefer[j])
                self.commits += 1
            if side != 0.0:
                keep[key] = side
        if prefer is not None:
            # ours (path_sides): two committed discs too close together for the robot to
            # pass between them with its personal space, committed to opposite sides (the
            # second was sensed after the first was committed), take the path's sides
            js = [j for j, i in enumerate(ids) if int(i) in keep]
            for a in js:
                for b in js:
                    ka, kb = int(ids[a]), int(ids[b])
                    if b <= a or keep[ka] == keep[kb]:
                        continue
                    d = math.hypot(float(dpos[a, 0] - dpos[b, 0]), float(dpos[a, 1] - dpos[b, 1]))
                    if d < float(drad[a] + drad[b]) + 2.0 * (radius + self.personal_m):
                        if prefer[a] != 0.0:
                            keep[ka] = float(prefer[a])
                        if prefer[b] != 0.0:
                            keep[kb] = float(prefer[b])
        self.committed = keep


def path_sides(pts: np.ndarray, k: int, dpos: np.ndarray, drad: np.ndarray, radius: float,
               personal_m: float, ahead_m: float = 8.0) -> np.ndarray:
    """The side (+1 left, -1 right, 0 none) of the path ``pts`` (from its point ``k``, over
    ``ahead_m`` of it) on which each disc lies, told at the path point nearest the disc
    against the path's direction there; 0 when the path passes farther than ``radius +
    drad + personal_m + 1 m`` or through it (ours, ``dwa``'s ``path_sides``).  A path
    planned around the discs, as the replanned one is, never goes between two discs
    closer together than the robot, so the discs of a group get one side.

    >>> pts = np.array([[0.0, 0.0], [2.0, 0.0], [4.0, 0.0]])
    >>> path_sides(pts, 0, np.array([[2.0, 0.9], [3.0, -0.8], [2.0, 5.0]]),
    ...            np.full(3, 0.25), 0.25, 0.5).tolist()
    [1.0, -1.0, 0.0]
    """
    out = np.zeros(drad.shape[0])
    m = pts.shape[0]
    for i in range(drad.shape[0]):
        best = math.inf
        side = 0.0
        run = 0.0
        j = max(0, min(int(k), m - 1))
        while j + 1 < m and run <= ahead_m:
            ax, ay = float(pts[j, 0]), float(pts[j, 1])
            vx, vy = float(pts[j + 1, 0]) - ax, float(pts[j + 1, 1]) - ay
            l2 = vx * vx + vy * vy
            run += math.sqrt(l2)
            j += 1
            if l2 <= 0.0:
                continue
            qx, qy = float(dpos[i, 0]) - ax, float(dpos[i, 1]) - ay
            u = min(1.0, max(0.0, (qx * vx + qy * vy) / l2))
            d = math.hypot(qx - u * vx, qy - u * vy)
            if d < best:
                best = d
                cr = vx * qy - vy * qx
                side = 1.0 if cr > 0.0 else -1.0
        if best < radius + float(drad[i]) + personal_m + COMMIT_M and best > 0.5 * radius:
            out[i] = side
    return out


EVERY_DISC = np.zeros(0, dtype=np.bool_)
"""The steady mask meaning every sensed disc (:func:`dwell_shortfall`)."""

STEADY_S = 1.0
"""A disc is *steady* (the dwell critic counts it) once it has kept its velocity this long."""
STEADY_RAD = math.radians(20.0)
"""... its direction within this of the present one ..."""
STEADY_SPEED_MPS = 0.1
"""... and its speed within this (or 20 % of the present speed, whichever is larger)."""


class SteadyDiscs:
    """Which sensed discs have kept their velocity over the last :data:`STEADY_S` (ours).

    The dwell critic extrapolates a disc's lane beyond the rollouts' horizon; that only
    makes sense for a disc that walks somewhere (a person on their way, a disc on a straight
    leg), not for one that wanders.  A disc is steady when it has been sensed for
    :data:`STEADY_S` and every velocity sensed in that time is within :data:`STEADY_RAD` of
    the present one's direction and within :data:`STEADY_SPEED_MPS` (or 20 %) of its speed;
    a disc slower than :data:`STEADY_SPEED_MPS` is steady (its lane is where it stands).

    Examples
    --------
    >>> sd = SteadyDiscs(dt=0.5)                 # two ticks make a second
    >>> ids = np.array([1, 2])
    >>> sd.update(ids, np.array([[1.0, 0.0], [1.0, 0.0]])).tolist()
    [False, False]
    >>> _ = sd.update(ids, np.array([[1.0, 0.0], [0.0, 1.0]]))   # disc 2 turns
    >>> sd.update(ids, np.array([[1.0, 0.05], [0.0, 1.0]])).tolist()
    [True, False]
    """

    def __init__(self, dt: float, steady_s: float = STEADY_S) -> None:
        self.n = max(1, int(round(steady_s / float(dt))))
        self.hist: dict[int, list[tuple[float, float]]] = {}
        self.wanders: set[int] = set()
        """The discs sensed for :data:`STEADY_S` that are not steady (the last update)."""

    def update(self, ids: np.ndarray, dvel: np.ndarray) -> np.ndarray:
        """Record this tick's velocities ``dvel`` of the discs ``ids``; the steady mask."""
        out = np.zeros(len(ids), dtype=np.bool_)
        hist: dict[int, list[tuple[float, float]]] = {}
        for j, i in enumerate(ids):
            h = self.hist.get(int(i), [])
            vx, vy = float(dvel[j, 0]), float(dvel[j, 1])
            h = (h + [(vx, vy)])[-(self.n + 1):]
            hist[int(i)] = h
            sp = math.hypot(vx, vy)
            if len(h) <= self.n:
                continue
            if sp < STEADY_SPEED_MPS:
                out[j] = True
                continue
            tol = max(STEADY_SPEED_MPS, 0.2 * sp)
            ok = True
            for ux, uy in h[:-1]:
                su = math.hypot(ux, uy)
                if abs(su - sp) > tol or su == 0.0:
                    ok = False
                    break
                c = (ux * vx + uy * vy) / (su * sp)
                if math.acos(max(-1.0, min(1.0, c))) > STEADY_RAD:
                    ok = False
                    break
            out[j] = ok
        self.hist = hist
        self.wanders = {int(i) for j, i in enumerate(ids)
                        if len(hist[int(i)]) > self.n and not out[j]}
        return out

    def trusted(self, ids: np.ndarray) -> np.ndarray:
        """A boolean mask of the discs ``ids`` not seen to wander at the last update: those
        whose constant-velocity lanes the fusion's replanned lanes and the lane escapes trust."""
        return np.array([int(i) not in self.wanders for i in ids], dtype=np.bool_)


def disc_ids(obs: Any, n: int) -> np.ndarray:
    """The sensed discs' identities (their indices in the scenario), or ``0..n-1`` when the
    observation carries none."""
    ids = getattr(obs.obstacles, "ids", None)
    if ids is None or len(ids) != n:
        return np.arange(n)
    return np.asarray(ids)


@njit(cache=True)
def _lane_shortfall(px, py, t, qx, qy, vx, vy, rd, radius, dwell_s, personal_m):
    """One disc's term of :func:`dwell_shortfall`."""
    ax = qx + vx * t
    ay = qy + vy * t
    bx = vx * dwell_s
    by = vy * dwell_s
    l2 = bx * bx + by * by
    u = 0.0
    if l2 > 0.0:
        u = min(1.0, max(0.0, ((px - ax) * bx + (py - ay) * by) / l2))
    g = math.hypot(px - ax - u * bx, py - ay - u * by) - radius - rd
    if g < personal_m:
        return (personal_m - max(g, 0.0)) / personal_m * (1.0 - 0.5 * u)
    return 0.0


@njit(cache=True)
def dwell_shortfall(px, py, t, dpos, dvel, drad, radius, dwell_s, personal_m, steady):
    """The dwell critic of a rollout ending at ``(px, py)`` at time ``t`` (see the module
    docstring): over the sensed discs ``i`` with ``steady[i]`` (every disc when ``steady``
    is empty), the largest ``(personal_m - gap) / personal_m`` (gap clipped at 0) times
    ``1 - u / 2``, where ``gap`` is the least distance between the robot's disc standing
    there and disc ``i`` moving on from ``dpos[i] + dvel[i] t`` at ``dvel[i]`` for
    ``dwell_s``, and ``u`` in [0, 1] is when in ``dwell_s`` it comes closest.  0 when no
    such disc comes within ``personal_m``.

    Examples
    --------
    >>> z = np.zeros((1, 2))
    >>> v = np.array([[0.0, 1.0]])               # a disc walking along +y at x = 3
    >>> r = np.array([0.25])
    >>> p = np.array([[3.0, -1.0]])
    >>> every = np.zeros(0, dtype=np.bool_)
    >>> round(dwell_shortfall(3.0, 0.0, 0.0, p, v, r, 0.25, 1.5, 0.5, every), 3)  # in its lane
    0.667
    >>> dwell_shortfall(1.5, 0.0, 0.0, p, v, r, 0.25, 1.5, 0.5, every)   # 1.5 m beside it
    0.0
    >>> dwell_shortfall(3.0, 0.0, 0.0, p, z, r, 0.25, 1.5, 0.5, every)   # standing 1 m away
    0.0
    >>> dwell_shortfall(3.0, 0.0, 0.0, p, v, r, 0.25, 1.5, 0.5, np.array([False]))  # wanders
    0.0
    """
    worst = 0.0
    every = steady.shape[0] == 0
    for i in range(drad.shape[0]):
        if every or steady[i]:
            sh = _lane_shortfall(px, py, t, dpos[i, 0], dpos[i, 1], dvel[i, 0], dvel[i, 1],
                                 drad[i], radius, dwell_s, personal_m)
            if sh > worst:
                worst = sh
    return worst
