"""A planning problem, validated once: the map, the start, the goal, the robot radius, the budget.

:meth:`Problem.create` checks the input (a bad value is a
:class:`~pathfuse.result.QueryError` or :class:`~pathfuse.result.ConfigError`
naming it) and fixes the start and goal cells with scalar arithmetic, so
the planners trust a problem and never check it again.  Whether the start
and the goal can be planned from at all (inside the map, not blocked) is an
*outcome*, not bad input: :meth:`Problem.failure` gives the status.

Examples
--------
>>> from pathfuse.grid import GridMap
>>> g = GridMap.from_rows(["....", ".##.", "...."])
>>> p = Problem.create(g, (0.5, 0.5), (3.5, 2.5))
>>> p.start_cell, p.goal_cell, p.failure()
((0, 0), (2, 3), None)
>>> Problem.create(g, (1.5, 1.5), (3.5, 2.5)).failure()[0].name
'START_OCCUPIED'
>>> status, message = Problem.create(g, (0.5, 0.5), (9.0, 0.5)).failure()
>>> status.name, message
('GOAL_OUT_OF_BOUNDS', 'goal (9, 0.5) is outside the map [0, 4) x [0, 3)')
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from pathfuse.grid import GridMap
from pathfuse.result import Budget, ConfigError, QueryError, Status
from pathfuse.validate import point
from pathfuse.validate import short as _shown

__all__ = ["Problem"]

_DEFAULT_BUDGET = Budget()


@dataclass(frozen=True, eq=False)
class Problem:
    """A planning query that planners trust (build it with :meth:`create`).

    Attributes
    ----------
    grid : GridMap
        The static map.
    start, goal : (float, float)
        World coordinates in metres.
    robot_radius_m : float
        Radius of the disc robot (0: a point).  Planners keep this clearance
        from every occupied square and from the map's edge; the global
        planner searches :meth:`GridMap.cspace`.
    budget : Budget
        Iteration and time caps.
    start_cell, goal_cell : (int, int)
        ``(row, col)`` of the cells the points lie in (may be outside the
        map: see :meth:`failure`).
    clearance_m : float
        The soft safety margin beyond the radius (ours; 0 = off): the global
        planner pays for coming closer to an obstacle, the controllers keep
        it where they can (see the robots guide, docs/guide/robots.md).
    robot : RobotModel or None
        The robot's kinematic model (:class:`pathfuse.robot.RobotModel`);
        None: a holonomic robot (offline, the geometric planners ignore it;
        ``dwa`` plans with a default diff-drive robot).
    """

    grid: GridMap
    start: tuple[float, float]
    goal: tuple[float, float]
    robot_radius_m: float = 0.0
    budget: Budget = field(default=_DEFAULT_BUDGET)
    start_cell: tuple[int, int] = (0, 0)
    goal_cell: tuple[int, int] = (0, 0)
    clearance_m: float = 0.0
    robot: Any = None

    @property
    def inflation_m(self) -> float:
        """The global planner's margin (ours): the larger of ``clearance_m`` and the
        robot's ``inflation_m`` (0 without a robot)."""
        rb = self.robot
        return max(self.clearance_m, float(rb.inflation_m) if rb is not None else 0.0)

    @classmethod
    def create(cls, grid: GridMap, start: object, goal: object, robot_radius_m: float = 0.0,
               budget: Budget | None = None, clearance_m: float = 0.0,
               robot: Any = None) -> Problem:
        """Check the input once and fix the cells (scalar arithmetic, no numpy per point).

        Raises
        ------
        QueryError
            ``grid`` is not a :class:`GridMap`, or ``start``/``goal`` is not a
            pair of finite numbers.
        ConfigError
            ``robot_radius_m`` or ``clearance_m`` is not a finite number >= 0,
            ``budget`` is not a :class:`Budget`, or ``robot`` is not a
            :class:`~pathfuse.robot.RobotModel` of radius ``robot_radius_m``.
        """
        if not isinstance(grid, GridMap):
            raise QueryError(f"grid: must be a pathfuse.GridMap, got {type(grid).__name__}")
        # two finite floats in a tuple (plan()'s usual call) need no call of point()
        if type(start) is tuple and len(start) == 2 and type(start[0]) is float and \
                type(start[1]) is float and math.isfinite(start[0]) and \
                math.isfinite(start[1]):
            s: tuple[float, float] = start  # type: ignore[assignment]
        else:
            s = point(start, "start", QueryError)
        if type(goal) is tuple and len(goal) == 2 and type(goal[0]) is float and \
                type(goal[1]) is float and math.isfinite(goal[0]) and math.isfinite(goal[1]):
            g: tuple[float, float] = goal  # type: ignore[assignment]
        else:
            g = point(goal, "goal", QueryError)
        if budget is None:
            budget = _DEFAULT_BUDGET
        elif not isinstance(budget, Budget):
            raise ConfigError(f"budget: must be a pathfuse.Budget, got {type(budget).__name__}")
        r = robot_radius_m
        if isinstance(r, bool) or not isinstance(r, (int, float)) or not math.isfinite(r) \
                or r < 0:
            try:
                r = float(r)  # numpy scalars
                ok = math.isfinite(r) and r >= 0
            except (TypeError, ValueError):
                ok = False
            if not ok:
                raise ConfigError(
                    f"robot_radius_m: must be a finite number >= 0, got {_shown(robot_radius_m)}")
        c = clearance_m
        if c != 0.0:
            if isinstance(c, bool) or not isinstance(c, (int, float)) or not math.isfinite(c) \
                    or c < 0:
                raise ConfigError(f"clearance_m: must be a finite number >= 0, got {_shown(c)}")
            c = float(c)
        if robot is not None:
            from pathfuse.robot import RobotModel

            if not isinstance(robot, RobotModel):
                raise ConfigError(f"robot: must be a pathfuse.RobotModel, got "
                                  f"{type(robot).__name__}")
            if robot.radius_m != float(r):
                raise ConfigError(f"robot: its radius_m ({robot.radius_m:g}) differs from "
                                  f"robot_radius_m ({float(r):g})")
        ox, oy = grid.origin
        res = grid.resolution
        return cls._made(grid, s, g, float(r), budget,
                         (math.floor((s[1] - oy) / res), math.floor((s[0] - ox) / res)),
                         (math.floor((g[1] - oy) / res), math.floor((g[0] - ox) / res)),
                         c, robot)

    @classmethod
    def _made(cls, grid: GridMap, start: tuple[float, float], goal: tuple[float, float],
              robot_radius_m: float, budget: Budget, start_cell: tuple[int, int],
              goal_cell: tuple[int, int], clearance_m: float, robot: Any) -> Problem:
        """``cls(...)`` with every field given, for values already checked: the fields are
        stored as the frozen dataclass's ``__init__`` stores them, without its
        ``object.__setattr__`` call per field (0.75 of the 3 us that :meth:`create` cost; a
        tiny ``plan()`` is 17 us)."""
        obj = object.__new__(cls)
        d = obj.__dict__
        d["grid"] = grid
        d["start"] = start
        d["goal"] = goal
        d["robot_radius_m"] = robot_radius_m
        d["budget"] = budget
        d["start_cell"] = start_cell
        d["goal_cell"] = goal_cell
        d["clearance_m"] = clearance_m
        d["robot"] = robot
        return obj

    def failure(self) -> tuple[Status, str] | None:
        """``(status, message)`` when the start or goal cannot be planned from, else None.

        Out of the map: ``START_/GOAL_OUT_OF_BOUNDS``.  Blocked: a point robot
        in an occupied (or, on a ROS map, unknown) cell, or a disc robot that
        overlaps an occupied square or the map's edge:
        ``START_/GOAL_OCCUPIED``.
        """
        g = self.grid
        h, w = g.occupied.shape
        occ = g.occupied
        (sr, sc), (gr, gc) = self.start_cell, self.goal_cell
        # the common case first: both cells inside, free, and a point robot
        if 0 <= sr < h and 0 <= sc < w and 0 <= gr < h and 0 <= gc < w and \
                not occ[sr, sc] and not occ[gr, gc] and self.robot_radius_m == 0:
            return None
        for p, cell, what, oob, blocked in (
            (self.start, self.start_cell, "start", Status.START_OUT_OF_BOUNDS,
             Status.START_OCCUPIED),
            (self.goal, self.goal_cell, "goal", Status.GOAL_OUT_OF_BOUNDS, Status.GOAL_OCCUPIED),
        ):
            r, c = cell
            if not (0 <= r < h and 0 <= c < w):
                x0, y0, x1, y1 = g.bounds
                return oob, (f"{what} ({p[0]:g}, {p[1]:g}) is outside the map "
                             f"[{x0:g}, {x1:g}) x [{y0:g}, {y1:g})")
            msg = self._blocked(p, cell, what)
            if msg is not None:
                return blocked, msg
        return None

    def _blocked(self, p: tuple[float, float], cell: tuple[int, int], what: str) -> str | None:
        from numpy import shape as np_shape

        g = self.grid
        r, c = cell
        if g.occupied[r, c]:
            unknown = g.meta.get("unknown")
            if unknown is not None and bool(unknown[r, c]):
                return (f"{what} ({p[0]:g}, {p[1]:g}) lies in an unknown cell of the map "
                        "(unknown cells are blocked; load the map with unknown='free' to "
                        "plan through them)")
            return f"{what} ({p[0]:g}, {p[1]:g}) lies in an occupied cell"
        if self.robot_radius_m > 0:
            from pathfuse.costmap import costmap_for, make_costmap, move_clear

            # the clearance every controller keeps (the radius plus a sliver), so that a
            # robot allowed to start or stop here can also move away or arrive
            cm = costmap_for(g, self.robot_radius_m, lattice=False)
            clear = cm.clear_m
            if not move_clear(cm, p[0], p[1], p[0], p[1], clear):
                x0, y0, x1, y1 = g.bounds
                edge = min(p[0] - x0, x1 - p[0], p[1] - y0, y1 - p[1]) < self.robot_radius_m
                unknown = g.meta.get("unknown")
                if edge:
                    hit = "the map's edge"
                elif unknown is not None and np_shape(unknown) == g.occupied.shape and \
                        move_clear(make_costmap(g.occupied & ~unknown, self.robot_radius_m,
                                                origin=g.origin, resolution_m=g.resolution,
                                                lattice=False), p[0], p[1], p[0], p[1], clear):
                    hit = ("an unknown cell of the map (unknown cells are blocked; load the "
                           "map with unknown='free' to plan through them)")
                else:
                    hit = "an occupied cell"
                return (f"{what} ({p[0]:g}, {p[1]:g}): the robot (radius "
                        f"{self.robot_radius_m:g} m) overlaps {hit}")
        return None

    def with_start(self, start: tuple[float, float]) -> Problem:
        """The same problem from another start (a replanning robot's position)."""
        ox, oy = self.grid.origin
        res = self.grid.resolution
        return Problem._made(self.grid, start, self.goal, self.robot_radius_m, self.budget,
                             (math.floor((start[1] - oy) / res),
                              math.floor((start[0] - ox) / res)),
                             self.goal_cell, self.clearance_m, self.robot)
