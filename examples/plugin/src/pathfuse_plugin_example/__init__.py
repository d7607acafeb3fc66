"""An example pathfuse plug-in: ``bfs4``, a 4-connected breadth-first global planner.

The package declares one entry point in the group ``pathfuse.planners`` (see its
``pyproject.toml``): :func:`register`, which pathfuse calls the first time its
planner registry is consulted.  It registers

* the global planner ``bfs4``: the fewest straight moves (no diagonals) between the
  start and goal cells on the robot's c-space, as waypoints in metres; every planner
  with a ``global_planner`` parameter (``astar``, ``fusion``, ``dwa``, ...) can follow
  it (``pathfuse plan --planner fusion --global-planner bfs4``);
* the planner ``bfs4``: a preset of that global planner and pathfuse's path
  follower (``pathfuse plan --planner bfs4``).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

import pathfuse
from pathfuse.planners.params import GlobalChoice, PursuitParams
from pathfuse.validate import param

__all__ = ["register", "bfs4", "BFS4Params"]

_MOVES = ((0, 1), (1, 0), (0, -1), (-1, 0))


def bfs4(problem):
    """The 4-connected path with the fewest moves, as (N, 2) waypoints in metres, or None.

    ``problem`` is a :class:`pathfuse.Problem` whose start and goal pathfuse has
    checked (inside the map, free for the robot disc).
    """
    grid = problem.grid
    blocked = grid.cspace(problem.robot_radius_m).occupied
    h, w = blocked.shape
    start, goal = tuple(problem.start_cell), tuple(problem.goal_cell)
    if blocked[start] or blocked[goal]:
        return None  # a disc robot whose cell is not free in the c-space
    parent = {start: start}
    todo = deque([start])
    while todo:
        cell = todo.popleft()
        if cell == goal:
            break
        r, c = cell
        for dr, dc in _MOVES:
            nxt = (r + dr, c + dc)
            if 0 <= nxt[0] < h and 0 <= nxt[1] < w and not blocked[nxt] and nxt not in parent:
                parent[nxt] = cell
                todo.append(nxt)
    if goal not in parent:
        return None
    cells = [goal]
    while cells[-1] != start:
        cells.append(parent[cells[-1]])
    cells.reverse()
    ox, oy = grid.origin
    res = grid.resolution
    centres = [(ox + (c + 0.5) * res, oy + (r + 0.5) * res) for r, c in cells]
    pts = [tuple(problem.start), *centres, tuple(problem.goal)]
    keep = [p for i, p in enumerate(pts) if i == 0 or p != pts[i - 1]]
    return np.array(keep, dtype=float)


@dataclass(frozen=True)
class BFS4Params(PursuitParams, GlobalChoice):
    """Parameters of the ``bfs4`` planner: pathfuse's path follower's, and the global planner
    it follows (``bfs4`` unless set)."""

    global_planner: str = param("bfs4", help="the global planner the follower follows")


def register() -> None:
    """The entry point: register the global planner ``bfs4`` and the planner ``bfs4``."""
    pathfuse.register_global_planner(
        "bfs4", bfs4, description="4-connected breadth-first search, fewest straight moves "
                                  "(example plug-in)")
    pathfuse.register(pathfuse.PlannerSpec(
        name="bfs4", params_cls=BFS4Params,
        description="follow the 4-connected breadth-first path (example plug-in)",
        controller=pathfuse.get_controller("follow"), global_planner="bfs4"))
