"""Recovery behaviours of an online controller that stalls or oscillates (ours, after Nav2).

Nav2's navigator runs a *recovery* subtree when the controller fails: clear
the costmaps, spin, wait, back up, retry.  :class:`RecoveryMonitor` does that
for every online controller of pathfuse (:meth:`Controller.command
<pathfuse.planners.base.Controller.command>`), between the controller and the
safety shield, so every recovery command is checked like any other.

Detection (every tick, from the observed positions):

* **stall**: the robot moved less than ``stall_m`` (0.3 m) over the last
  ``stall_s`` (5 s);
* **oscillation**: over the last ``oscillation_s`` (10 s) it travelled more
  than ``oscillation_ratio`` (4) times its net displacement, and that
  displacement is under 1 m (going back and forth, or circling).

Each detection runs the next behaviour of the cycle (the first again once
the robot has got ``progress_m`` (1 m) away from where the last one
started):

1. ``clear`` (Nav2's clear-costmap): the controller drops its obstacle
   critics for ``clear_s`` (3 s) and replans its global path, where it knows
   how (:meth:`Controller.relax <pathfuse.planners.base.Controller.relax>`:
   ``dwa`` and the velocity-space fusion); the shield keeps the robot clear
   meanwhile.  A controller without critics to drop skips to the next.
2. ``spin`` (a diff-drive robot): turn on the spot by a quarter turn towards
   the global path's bearing (``lookahead`` 1 m along it), at the rate from
   which the turn can stop there; at most 3 s.
3. ``back_up``: reverse 0.3 m at 0.15 m/s (a diff-drive robot with a
   negative ``min_speed_mps``; a holonomic robot moves back along the way it
   came); at most 3 s.  A diff-drive robot that cannot reverse ``wait`` s
   instead: stands for 2 s (a moving obstacle may clear the way).

It runs for ``dwa``, ``mppi``, the path followers and the velocity-space
fusion; the potential-field controllers on their own (``apf``, ``ref6``,
``ref7`` and the fusion on a holonomic robot) keep their own stall handling
(Algorithm 2's escape), on which the paper's and the holonomic results rest.
``robot.recovery: false`` (:class:`~pathfuse.robot.RobotModel`) switches it
off.  :attr:`RecoveryMonitor.counts` counts each behaviour started.

Examples
--------
>>> m = RecoveryMonitor(dt=0.1, diff_drive=True, can_reverse=False)
>>> m.behaviours
('clear', 'spin', 'wait')
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

__all__ = ["RecoveryMonitor", "BEHAVIOURS"]

BEHAVIOURS = ("clear", "spin", "back_up", "wait")
"""The recovery behaviours, in the order :attr:`RecoveryMonitor.counts` lists them."""


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


class RecoveryMonitor:
    """Stall and oscillation detection, and the recovery cycle (see the module docstring).

    Parameters
    ----------
    dt : float
        The tick (s).
    diff_drive : bool
        The robot's model (a holonomic robot does not spin).
    can_reverse : bool
        Whether the robot may drive backwards (``min_speed_mps < 0``; always true
        for a holonomic robot).
    max_yaw_rate, max_yaw_accel : float
        Diff-drive limits for the spin (rad/s, rad/s^2).
    """

    stall_s = 5.0
    stall_m = 0.3
    oscillation_s = 10.0
    oscillation_ratio = 4.0
    progress_m = 1.0
    clear_s = 3.0
    behaviour_s = 3.0
    back_up_m = 0.3
    back_up_mps = 0.15
    wait_s = 2.0

    def __init__(self, dt: float, diff_drive: bool, can_reverse: bool,
                 max_yaw_rate: float = math.inf, max_yaw_accel: float = math.inf) -> None:
        self.dt = float(dt)
        self.diff_drive = bool(diff_drive)
        self.can_reverse = bool(can_reverse) or not diff_drive
        self.max_yaw_rate = float(max_yaw_rate)
        self.max_yaw_accel = float(max_yaw_accel)
        cycle = ["clear"]
        if diff_drive:
            cycle.append("spin")
        cycle.append("back_up" if self.can_reverse else "wait")
        self.behaviours: tuple[str, ...] = tuple(cycle)
        n = max(2, int(round(self.oscillation_s / self.dt)) + 1)
        self.trail = np.full((n, 2), np.nan)
        self.steps = np.zeros(n)  # the distance moved in each tick (for the oscillation test)
        self.n_stall = max(1, int(round(self.stall_s / self.dt)))
        self.ticks = 0
        self.quiet_until = 0
        self.next_k = 0
        self.anchor: np.ndarray | None = None
        self.counts = {b: 0 for b in BEHAVIOURS}
        self.active: str | None = None
        self.left = 0
        self.target = 0.0
        self.start = np.zeros(2)
        self.away = np.zeros(2)

    # ----------------------------------------------------------------- detection
    def _observe(self, p: np.ndarray) -> str | None:
        n = self.trail.shape[0]
        i = self.ticks % n
        prev = self.trail[(i - 1) % n]
        self.steps[i] = math.hypot(p[0] - prev[0], p[1] - prev[1]) if np.isfinite(prev[0]) \
            else 0.0
        self.trail[i] = p
        self.ticks += 1
        if self.anchor is not None and math.hypot(p[0] - self.anchor[0],
                                                  p[1] - self.anchor[1]) >= self.progress_m:
            self.next_k = 0  # it got away: the cycle starts over
            self.anchor = None
        if self.ticks < self.quiet_until:
            return None
        if self.ticks > self.n_stall:
            old = self.trail[(self.ticks - 1 - self.n_stall) % n]
            if math.hypot(p[0] - old[0], p[1] - old[1]) < self.stall_m:
                return "stall"
        if self.ticks >= n:
            old = self.trail[self.ticks % n]
            net = math.hypot(p[0] - old[0], p[1] - old[1])
            travelled = float(self.steps.sum()) - self.steps[self.ticks % n]
            if net < self.progress_m and travelled > self.oscillation_ratio * max(net, 0.25):
                return "oscillation"
        return None

    def step(self, position: np.ndarray, heading: float, bearing: Callable[[], float | None],
             relax: Callable[[float], bool]) -> np.ndarray | None:
        """The recovery command for this tick, or None (the controller acts).

        ``bearing()`` gives the direction of the global path ahead (or None);
        ``relax(seconds)`` asks the controller to drop its obstacle critics
        (True when it can).
        """
        p = np.asarray(position, dtype=np.float64)
        why = self._observe(p)
        if self.active is None and why is not None:
            self._begin(p, heading, bearing, relax)
        if self.active is None:
            return None
        return self._command(p, heading)

    def _begin(self, p: np.ndarray, heading: float, bearing: Callable[[], float | None],
               relax: Callable[[float], bool]) -> None:
        if self.anchor is None:
            self.anchor = p.copy()
        for _ in range(len(self.behaviours)):
            b = self.behaviours[self.next_k % len(self.behaviours)]
            self.next_k += 1
            if b == "clear":
                if relax(self.clear_s):
                    self.counts[b] += 1
                    self._settle(self.clear_s)
                    return
                continue
            self.counts[b] += 1
            self.active = b
            self.start = p.copy()
            if b == "spin":
                to = bearing()
                err = _wrap(to - heading) if to is not None else 1.0
                self.target = heading + math.copysign(min(abs(err), math.pi / 2.0), err) \
                    if abs(err) > 0.2 else heading + math.copysign(math.pi / 2.0, err or 1.0)
                self.left = int(round(self.behaviour_s / self.dt))
            elif b == "back_up":
                n = self.trail.shape[0]
                old = self.trail[(self.ticks - 1 - min(self.n_stall, self.ticks - 1)) % n]
                d = p - old if np.isfinite(old[0]) else np.zeros(2)
                nd = math.hypot(d[0], d[1])
                # a holonomic robot goes back the way it came (or turns round its heading)
                self.away = -d / nd if nd > 1e-9 else -np.array([math.cos(heading),
                                                                 math.sin(heading)])
                self.left = int(round(self.behaviour_s / self.dt))
            else:
                self.left = int(round(self.wait_s / self.dt))
            self._settle(self.left * self.dt)
            return

    def _settle(self, seconds: float) -> None:
        # no new detection until the behaviour has run and the trail shows its effect
        self.quiet_until = self.ticks + int(round(seconds / self.dt)) + self.n_stall // 2

    def _command(self, p: np.ndarray, heading: float) -> np.ndarray | None:
        b = self.active
        self.left -= 1
        done = self.left < 0
        out: np.ndarray | None = None
        if b == "spin":
            err = _wrap(self.target - heading)
            if abs(err) < 0.05:
                done = True
            else:
                rate = min(abs(err) / self.dt, self.max_yaw_rate)
                if math.isfinite(self.max_yaw_accel):
                    rate = min(rate, math.sqrt(2.0 * self.max_yaw_accel * abs(err)))
                out = np.array([0.0, math.copysign(rate, err)])
        elif b == "back_up":
            if math.hypot(p[0] - self.start[0], p[1] - self.start[1]) >= self.back_up_m:
                done = True
            elif self.diff_drive:
                out = np.array([-self.back_up_mps, 0.0])
            else:
                out = self.away * self.back_up_mps
        else:  # wait
            out = np.zeros(2)
        if done or out is None:
            self.active = None
            return None
        return out
