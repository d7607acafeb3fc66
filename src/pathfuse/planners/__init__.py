"""Planners: a global planner plus a local controller, every one registered in
:mod:`pathfuse.planners.registry`.

* :mod:`~pathfuse.planners.global_astar` - the global planner (grid A* on the
  robot's c-space);
* :mod:`~pathfuse.planners.base` - the controller interface and the shared
  potential-field controller;
* :mod:`~pathfuse.planners.astar`, :mod:`~pathfuse.planners.apf`,
  :mod:`~pathfuse.planners.fusion`, :mod:`~pathfuse.planners.refs` - the
  built-in planners;
* :mod:`~pathfuse.planners.run` - running a planner offline or online.
"""

from pathfuse.planners.registry import (
    REGISTRY,
    PlannerSpec,
    get_planner,
    make_params,
    planner_names,
    register,
    register_function,
)

__all__ = ["REGISTRY", "PlannerSpec", "get_planner", "make_params", "planner_names", "register",
           "register_function"]
