"""pathfuse: 2-D grid path planning with exact fast A*, artificial potential fields and
the A*-APF fusion planner of Ju, Luo and Yan.

Every name below is imported on first use (PEP 562), so ``import pathfuse``
loads neither numpy, numba nor scipy: the command line starts fast, and a
program pays only for what it uses.

>>> import pathfuse
>>> g = pathfuse.GridMap.from_rows(["...", ".#.", "..."])
>>> bool(pathfuse.plan(g, (0.5, 0.5), (2.5, 2.5)))
True
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from pathfuse._version import __version__

_EXPORTS: dict[str, str] = {
    "GridMap": "pathfuse.grid",
    "plan": "pathfuse.api",
    "Problem": "pathfuse.problem",
    "Status": "pathfuse.result",
    "PlanResult": "pathfuse.result",
    "Budget": "pathfuse.result",
    "PathfuseError": "pathfuse.result",
    "MapError": "pathfuse.result",
    "MapFormatError": "pathfuse.result",
    "QueryError": "pathfuse.result",
    "ConfigError": "pathfuse.result",
    "PlanningFailed": "pathfuse.result",
    "LimitError": "pathfuse.limits",
    "REGISTRY": "pathfuse.planners.registry",
    "PlannerSpec": "pathfuse.planners.registry",
    "get_planner": "pathfuse.planners.registry",
    "planner_names": "pathfuse.planners.registry",
    "register_function": "pathfuse.planners.registry",
    "register": "pathfuse.planners.registry",
    "register_global_planner": "pathfuse.planners.registry",
    "register_controller": "pathfuse.planners.registry",
    "get_controller": "pathfuse.planners.registry",
    "global_planner_names": "pathfuse.planners.registry",
    "controller_names": "pathfuse.planners.registry",
    "load_map": "pathfuse.io",
    "map_from_spec": "pathfuse.io",
    "read_movingai": "pathfuse.io",
    "write_movingai": "pathfuse.io",
    "read_scen": "pathfuse.io",
    "read_ros_map": "pathfuse.io",
    "write_ros_map": "pathfuse.io",
    "read_image": "pathfuse.io",
    "read_npy": "pathfuse.io",
    "read_rows_yaml": "pathfuse.io",
    "simulate": "pathfuse.world.episode",
    "Episode": "pathfuse.world.episode",
    "World": "pathfuse.world.world",
    "load_scenario": "pathfuse.world.scenario",
    "RobotModel": "pathfuse.robot",
}

__all__ = [
    "GridMap",
    "plan",
    "Problem",
    "Status",
    "PlanResult",
    "Budget",
    "PathfuseError",
    "MapError",
    "MapFormatError",
    "QueryError",
    "ConfigError",
    "PlanningFailed",
    "LimitError",
    "REGISTRY",
    "PlannerSpec",
    "get_planner",
    "planner_names",
    "register_function",
    "register",
    "register_global_planner",
    "register_controller",
    "get_controller",
    "global_planner_names",
    "controller_names",
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
    "Episode",
    "World",
    "load_scenario",
    "RobotModel",
    "__version__",
]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'pathfuse' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)


if TYPE_CHECKING:  # what the names are, for type checkers and IDEs
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
    from pathfuse.limits import LimitError
    from pathfuse.planners.registry import (
        REGISTRY,
        PlannerSpec,
        controller_names,
        get_controller,
        get_planner,
        global_planner_names,
        planner_names,
        register,
        register_controller,
        register_function,
        register_global_planner,
    )
    from pathfuse.problem import Problem
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
    from pathfuse.robot import RobotModel
    from pathfuse.world.episode import Episode, simulate
    from pathfuse.world.scenario import load_scenario
    from pathfuse.world.world import World
