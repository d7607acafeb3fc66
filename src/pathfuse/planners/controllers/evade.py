"""Evasion out of a walker's swept lane (ours, issue 17/18; the fusion's ``evade``).

A disc that does not react walks into a robot standing in its way; the shield's passive
safety only promises that the robot is at rest when that happens.  Replayed on the tuning
family of the dynamic benchmark (``--seed 1``, diff-drive, 2 discs, scenarios 0 and 18), the
fusion's MPPI sequences slowed in front of a disc coming at it and stood (or turned on the
spot) in its lane until walked into: the sequences' critics weigh the path and the goal
against the disc, and MPPI's lane escape
(:mod:`pathfuse.planners.controllers.mppi_escape`) competes only once standing *where the
robot is* would be reached, by which time turning out takes most of the time left.

:class:`Evader` judges the planner's own plan geometrically instead: the optimal sequence
(MPPI's nominal, whose first step is the command) rolled out with the exact unicycle and
then held standing at its end for ``tail_s``, against every sensed disc predicted at
constant velocity (:func:`sequence_gap`: the least gap over the rollout *and* over the
stand after it, so a plan that ends in any disc's lane counts as the contact it leads
to).  When that gap is below ``trigger_m`` a fan of escape sequences (turn towards one of
:data:`EVADE_HEADINGS` headings as fast as the limits allow, then drive at full speed, as
MPPI's lane escape) is judged the same way, and the one with the largest gap (capped at
``enough_m``; ties go to the end nearest the goal) replaces the plan when it gains at least
``gain_m``.  The side is chosen against the sweeps of *all* sensed discs at once, and kept
(hysteresis): while an escape is committed its heading wins unless another gains
``gain_m`` more.  The command still goes through the shield like every command.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from pathfuse.costmap import segment_distance
from pathfuse.planners.controllers.mppi_escape import _towards
from pathfuse.sweep import unicycle_pose

__all__ = ["EVADE_HEADINGS", "sequence_gap", "Evader"]

EVADE_HEADINGS = 16
"""Headings of the escape fan, evenly spaced around the robot's (every 22.5 degrees)."""


@njit(cache=True)
def _stand_gap(x, y, t0, t1, radius, dpos, dvel, drad, spread):
    """The least gap between a robot standing at ``(x, y)`` from ``t0`` to ``t1`` and the
    discs predicted at constant velocity, each grown by ``spread`` m/s."""
    best = np.inf
    # the spread's share is bounded by its value at t1 (a conservative gap)
    grow = spread * t1
    for i in range(drad.shape[0]):
        ex = x - (dpos[i, 0] + dvel[i, 0] * t0)
        ey = y - (dpos[i, 1] + dvel[i, 1] * t0)
        vx = dvel[i, 0]
        vy = dvel[i, 1]
        v2 = vx * vx + vy * vy
        u = 0.0
        if v2 > 0.0:
            u = min(t1 - t0, max(0.0, (ex * vx + ey * vy) / v2))
        g = math.hypot(ex - u * vx, ey - u * vy) - radius - drad[i] - grow
        if g < best:
            best = g
    return best


@njit(cache=True)
def sequence_gap(cm, dt0, dt, seq, x, y, th, dpos, dvel, drad, tail_s, spread=0.0):
    """The least predicted gap (m) between the robot driving ``seq`` (``(v, omega)`` per
    step, the first ``dt0`` long, the others ``dt``) from ``(x, y, th)`` and then standing
    ``tail_s`` at its end, and the discs ``dpos, dvel, drad`` at constant velocity, each
    grown by ``spread`` m/s of elapsed time (their velocities are uncertain); ``-inf`` when
    a step's chord touches the static map (``cm.clear_m``).

    >>> from pathfuse.costmap import make_costmap
    >>> cm = make_costmap(np.zeros((20, 20), dtype=np.bool_), 0.25, resolution_m=0.5)
    >>> d = (np.array([[8.0, 5.0]]), np.array([[-1.0, 0.0]]), np.array([0.25]))
    >>> still = np.zeros((10, 2))
    >>> float(sequence_gap(cm, 0.1, 0.1, still, 5.0, 5.0, 0.0, *d, 3.0)) < 0   # walked into
    True
    >>> away = np.zeros((10, 2)); away[:, 0] = 1.0   # heading north at 1 m/s
    >>> round(float(sequence_gap(cm, 0.1, 0.1, away, 5.0, 5.0, 0.5 * np.pi, *d, 3.0)), 3)
    0.5
    """
    radius = cm.radius_m
    best = np.inf
    t = 0.0
    for k in range(seq.shape[0]):
        h = dt0 if k == 0 else dt
        nx, ny, nth = unicycle_pose(x, y, th, seq[k, 0], seq[k, 1], h)
        if segment_distance(cm, x, y, nx, ny, cm.clear_m) < cm.clear_m:
            return -np.inf
        t += h
        x, y, th = nx, ny, nth
        for i in range(drad.shape[0]):
            g = math.hypot(x - dpos[i, 0] - dvel[i, 0] * t,
                           y - dpos[i, 1] - dvel[i, 1] * t) - radius - drad[i] - spread * t
            if g < best:
                best = g
    g = _stand_gap(x, y, t, t + tail_s, radius, dpos, dvel, drad, spread)
    return min(best, g)


@njit(cache=True)
def _end(dt0, dt, seq, x, y, th):
    for k in range(seq.shape[0]):
        x, y, th = unicycle_pose(x, y, th, seq[k, 0], seq[k, 1], dt0 if k == 0 else dt)
    return x, y


@njit(cache=True)
def evade_fan(cm, f, x, y, th, c0, c1, dpos, dvel, drad, tail_s, spread, enough_m, goal_x,
              goal_y, keep_heading, keep_bonus, seqs, gaps, heads, order):
    """The fan of escape sequences into ``seqs`` (``EVADE_HEADINGS``, steps, 2), their gaps
    (capped at ``enough_m``) into ``gaps``, headings into ``heads`` and ``order`` best
    first: by gap (plus ``keep_bonus`` for the heading nearest ``keep_heading`` when that is
    finite), ties to the end nearest the goal."""
    key = np.empty(EVADE_HEADINGS)
    for i in range(EVADE_HEADINGS):
        hd = th + 2.0 * math.pi * i / EVADE_HEADINGS
        _towards(seqs[i], f, x, y, th, c0, c1, hd)
        g = min(sequence_gap(cm, f.dt_s, f.model_dt_s, seqs[i], x, y, th, dpos, dvel, drad,
                             tail_s, spread), enough_m)
        s = g
        if math.isfinite(keep_heading):
            e = (hd - keep_heading + math.pi) % (2.0 * math.pi) - math.pi
            if abs(e) <= math.pi / EVADE_HEADINGS + 1e-9:
                s += keep_bonus
        ex, ey = _end(f.dt_s, f.model_dt_s, seqs[i], x, y, th)
        # the gap first (in steps of a millimetre), then the end's distance to the goal; a
        # sequence into a wall (gap -inf) is clamped first: math.floor(-inf) in numba gives
        # the least int64, whose negation overflows and ranked such a sequence best, so that
        # the loop of Evader.choose stopped at it and no escape was ever taken where any
        # heading of the fan met a wall (every trigger in four replays of the tuning family)
        key[i] = -math.floor(max(s, -1e3) * 1000.0) * 1e6 + min(
            math.hypot(ex - goal_x, ey - goal_y), 1e5)
        gaps[i] = g
        heads[i] = hd
    order[:] = np.argsort(key)


class Evader:
    """The evasion state of one robot (see the module docstring).

    Parameters
    ----------
    goal : (float, float)
        The robot's goal (ties between equally safe escapes go to the end nearest it).
    tail_s : float
        How long the robot is predicted standing at the end of a sequence.
    trigger_m : float
        Escapes are tried when the plan's predicted gap is below this.
    gain_m : float
        An escape replaces the plan (or a committed escape another) only when its capped gap
        is larger by at least this.
    enough_m : float
        Gaps are capped here: beyond it an escape is as good as any other.
    hold_s : float
        An escape is kept committed (its heading preferred) this long after it was last
        chosen.
    dt : float
        The control tick.
    spread_mps : float
        Each disc's predicted position is grown by this much per second (its velocity is
        uncertain: random walkers turn).
    """

    def __init__(self, goal: tuple[float, float], tail_s: float = 3.0,
                 trigger_m: float = 0.3, gain_m: float = 0.1, enough_m: float = 0.5,
                 hold_s: float = 1.0, dt: float = 0.1, spread_mps: float = 0.2) -> None:
        self.spread = float(spread_mps)
        """Spread of the discs' predictions when escapes are compared (not in the trigger)."""
        self.gx, self.gy = float(goal[0]), float(goal[1])
        self.tail_s = float(tail_s)
        self.trigger_m = float(trigger_m)
        self.gain_m = float(gain_m)
        self.enough_m = float(enough_m)
        self.hold_ticks = max(1, int(round(hold_s / dt)))
        self.heading = math.nan
        self.left = 0
        self.evasions = 0
        """Ticks whose command came from an escape of the fan."""

    def choose(self, cm, f, x: float, y: float, th: float, c0: float, c1: float,
               nominal: np.ndarray, dpos: np.ndarray, dvel: np.ndarray,
               drad: np.ndarray, passes: Any = None, trigger: Any = None) -> bool:
        """Replace ``nominal`` in place by an escape when the plan's predicted gap is below
        ``trigger_m`` and the escape gains ``gain_m``; True when it did.  ``passes(v, w)``
        (the shield's test: True when the shield lets the command through unchanged) must
        accept an escape's first command: escapes the shield would hold back are skipped.
        ``trigger`` (a boolean mask of the discs, ours: ``evade_steady``) limits the trigger
        to the discs it marks (the discs seen steady; a wandering disc's constant-velocity
        prediction does not show its contact in time); the escapes are still judged against
        every disc."""
        if self.left > 0:
            self.left -= 1
        else:
            self.heading = math.nan
        if drad.shape[0] == 0:
            return False
        if trigger is not None:
            sel = np.flatnonzero(np.asarray(trigger, dtype=np.bool_)[:drad.shape[0]])
            if sel.shape[0] == 0:
                return False
            g0 = min(sequence_gap(cm, f.dt_s, f.model_dt_s, nominal, x, y, th,
                                  np.ascontiguousarray(dpos[sel]),
                                  np.ascontiguousarray(dvel[sel]),
                                  np.ascontiguousarray(drad[sel]), self.tail_s),
                     self.enough_m)
        else:
            g0 = min(sequence_gap(cm, f.dt_s, f.model_dt_s, nominal, x, y, th, dpos, dvel,
                                  drad, self.tail_s), self.enough_m)
        if g0 >= self.trigger_m:
            return False
        if self.spread > 0.0:
            g0 = min(sequence_gap(cm, f.dt_s, f.model_dt_s, nominal, x, y, th, dpos, dvel,
                                  drad, self.tail_s, self.spread), self.enough_m)
        seqs = np.empty((EVADE_HEADINGS, nominal.shape[0], 2))
        gaps = np.empty(EVADE_HEADINGS)
        heads = np.empty(EVADE_HEADINGS)
        order = np.empty(EVADE_HEADINGS, dtype=np.int64)
        evade_fan(cm, f, x, y, th, c0, c1, dpos, dvel, drad, self.tail_s, self.spread,
                  self.enough_m, self.gx, self.gy, self.heading if self.left > 0 else math.nan,
                  self.gain_m, seqs, gaps, heads, order)
        pick = -1
        for i in order:
            if not gaps[i] >= g0 + self.gain_m:
                break
            if passes is None or passes(float(seqs[i, 0, 0]), float(seqs[i, 0, 1])):
                pick = int(i)
                break
        if pick < 0:
            return False
        nominal[:, :] = seqs[pick]
        self.heading = float(heads[pick])
        self.left = self.hold_ticks
        self.evasions += 1
        return True
