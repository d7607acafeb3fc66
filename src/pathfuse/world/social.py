"""Social metrics of an episode among people: how close, how long, whose fault, how smooth.

:func:`social_metrics` is a pure numpy function of the sampled states of an
episode (the robot's positions at every tick, the people's positions and radii,
the tick length), so pathfuse's own episodes (:class:`pathfuse.world.Episode`,
where the moving discs are the people) and IR-SIM's
(:mod:`pathfuse.integrations.irsim`) are measured by the same definitions:

``min_gap_m``
    The least surface-to-surface distance between the robot disc and any
    person over the ticks (negative when they overlap; ``inf`` without people).
``time_within_m_s``
    Personal-space intrusion: the time (s) the gap to the nearest person was
    below ``personal_m`` (0.45 m by default, the near edge of Hall's personal
    zone), counted as ``dt`` for every tick after the first at which it was.
``at_fault_collisions``
    Contacts the robot drove into: the number of contact onsets (a tick at
    which the gap to a person is <= 0 while it was > 0 at the tick before, or
    the first tick) during whose tick the robot moved faster than
    ``moving_mps`` (0.01 m/s by default).  A person walking into a robot that
    stands still is a contact, not the robot's fault.
``contacts``
    Every contact onset, at fault or not.
``path_irregularity_rad_per_m``
    The total turning of the robot per metre driven: the sum of the absolute
    changes of its heading between ticks (the direction of travel when no
    heading is given; ticks in which the robot moves less than 1e-6 m keep
    the last direction) divided by the path length (0 for a path shorter than
    1 cm).  A straight run scores 0; spinning in place or weaving scores high.

Examples
--------
>>> t = 11
>>> robot = np.column_stack([np.linspace(0.0, 5.0, t), np.zeros(t)])
>>> person = np.column_stack([np.full(t, 2.5), np.full(t, 1.0)])[:, None, :]
>>> m = social_metrics(robot, person, np.array([0.25]), 0.25, 0.5)
>>> round(m.min_gap_m, 6), m.time_within_m_s, m.at_fault_collisions
(0.5, 0.0, 0)
>>> m = social_metrics(robot, person, np.array([0.25]), 0.25, 0.5, personal_m=0.6)
>>> m.time_within_m_s, m.path_irregularity_rad_per_m
(0.5, 0.0)
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

__all__ = ["SocialMetrics", "social_metrics", "PERSONAL_SPACE_M", "MOVING_MPS"]

PERSONAL_SPACE_M = 0.45
"""The gap below which a person's personal space is intruded (m)."""
MOVING_MPS = 0.01
"""The robot counts as moving during a tick above this speed (m/s)."""


@dataclass(frozen=True)
class SocialMetrics:
    """The social metrics of one episode (see the module docstring for the definitions)."""

    min_gap_m: float
    time_within_m_s: float
    at_fault_collisions: int
    contacts: int
    path_irregularity_rad_per_m: float
    personal_m: float = PERSONAL_SPACE_M

    def as_dict(self, prefix: str = "social_") -> dict[str, Any]:
        """The metrics as a flat dict with ``prefix`` on each key (``inf`` kept)."""
        return {f"{prefix}{k}": v for k, v in asdict(self).items()}


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def social_metrics(robot_positions: Any, people_positions: Any, people_radii: Any,
                   robot_radius_m: float, dt_s: float, *, headings: Any = None,
                   personal_m: float = PERSONAL_SPACE_M,
                   moving_mps: float = MOVING_MPS) -> SocialMetrics:
    """The social metrics of an episode.

    Parameters
    ----------
    robot_positions : (T, 2) array
        The robot's centre at every tick.
    people_positions : (T, K, 2) array
        Every person's centre at every tick (K may be 0; NaN rows: a person not
        present at that tick).
    people_radii : (K,) array
        The people's radii (m).
    robot_radius_m : float
        The robot's radius (m).
    dt_s : float
        The tick length (s).
    headings : (T,) array, optional
        The robot's heading at every tick (a diff-drive robot's; default: the
        direction of travel).
    personal_m, moving_mps : float
        The personal-space gap and the speed above which the robot is moving.

    Returns
    -------
    SocialMetrics

    Raises
    ------
    ValueError
        Arrays whose shapes do not agree (the message names them).
    """
    p = np.asarray(robot_positions, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 1:
        raise ValueError(f"robot_positions: must be a (T, 2) array with T >= 1, got shape "
                         f"{p.shape}")
    t = p.shape[0]
    q = np.asarray(people_positions, dtype=np.float64)
    r = np.asarray(people_radii, dtype=np.float64).reshape(-1)
    if q.size == 0:
        q = np.zeros((t, 0, 2))
    if q.ndim != 3 or q.shape[0] != t or q.shape[2] != 2 or q.shape[1] != r.shape[0]:
        raise ValueError(f"people_positions: must have shape ({t}, {r.shape[0]}, 2) for {t} "
                         f"ticks and {r.shape[0]} radii, got {q.shape}")
    step = np.hypot(*np.diff(p, axis=0).T) if t > 1 else np.zeros(0)
    length = float(step.sum())
    if headings is not None:
        h = np.asarray(headings, dtype=np.float64).reshape(-1)
        if h.shape[0] != t:
            raise ValueError(f"headings: must have {t} values (one per tick), got {h.shape[0]}")
        turn = float(np.abs(_wrap(np.diff(h))).sum()) if t > 1 else 0.0
    else:
        d = np.diff(p, axis=0)
        moving = step > 1e-6
        ang = np.arctan2(d[moving, 1], d[moving, 0]) if moving.any() else np.zeros(0)
        turn = float(np.abs(_wrap(np.diff(ang))).sum()) if ang.size > 1 else 0.0
    irregular = turn / length if length >= 0.01 else 0.0
    if r.shape[0] == 0:
        return SocialMetrics(math.inf, 0.0, 0, 0, irregular, float(personal_m))
    gaps = np.hypot(q[:, :, 0] - p[:, None, 0], q[:, :, 1] - p[:, None, 1]) - r[None, :] \
        - float(robot_radius_m)
    gaps = np.where(np.isnan(gaps), np.inf, gaps)
    nearest = gaps.min(axis=1)
    min_gap = float(nearest.min())
    within = float(np.count_nonzero(nearest[1:] < personal_m)) * float(dt_s)
    touch = gaps <= 0.0
    onset = touch.copy()
    onset[1:] &= ~touch[:-1]
    speed = np.concatenate([[0.0], step / float(dt_s)]) if dt_s > 0 else np.zeros(t)
    ticks = np.flatnonzero(onset.any(axis=1))
    contacts = int(np.count_nonzero(onset))
    fault = int(sum(int(np.count_nonzero(onset[k])) for k in ticks if speed[k] > moving_mps))
    return SocialMetrics(min_gap, within, fault, contacts, irregular, float(personal_m))
