"""pathfuse: 2-D grid path planning with exact fast A*, artificial potential fields and
the A*-APF fusion planner of Ju, Luo and Yan.

>>> import pathfuse
>>> g = pathfuse.GridMap.from_rows(["...", ".#.", "..."])
>>> bool(pathfuse.plan(g, (0.5, 0.5), (2.5, 2.5)))
True
"""

from pathfuse.api import plan
from pathfuse.grid import GridMap
from pathfuse.planners.registry import REGISTRY, get_planner, planner_names
from pathfuse.result import (
    Budget,
    ConfigError,
    MapError,
    MapFormatError,
    PathfuseError,
    PlanningFailed,
    PlanResult,
    QueryError,
    Status,
)

__version__ = "0.1.0"

__all__ = [
    "GridMap",
    "plan",
    "Status",
    "PlanResult",
    "Budget",
    "PathfuseError",
    "MapError",
    "MapFormatError",
    "QueryError",
    "ConfigError",
    "PlanningFailed",
    "REGISTRY",
    "get_planner",
    "planner_names",
    "__version__",
]
