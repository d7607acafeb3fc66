"""pathfuse: 2-D grid path planning with exact fast A*, artificial potential fields and
the A*-APF fusion planner of Ju, Luo and Yan.

>>> import pathfuse
>>> g = pathfuse.GridMap.from_rows(["...", ".#.", "..."])
>>> bool(pathfuse.plan(g, (0.5, 0.5), (2.5, 2.5)))
True
"""

from pathfuse.api import plan
from pathfuse.grid import GridMap
from pathfuse.io import (
    load_map,
    map_from_spec,
    read_image,
    read_movingai,
    read_npy,
    read_ros_map,
    read_rows_yaml,
    read_scen,
    write_movingai,
    write_ros_map,
)
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
from pathfuse.world import Episode, World, load_scenario, simulate

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
    "load_map",
    "map_from_spec",
    "read_movingai",
    "write_movingai",
    "read_scen",
    "read_ros_map",
    "write_ros_map",
    "read_image",
    "read_npy",
    "read_rows_yaml",
    "simulate",
    "World",
    "Episode",
    "load_scenario",
    "__version__",
]
