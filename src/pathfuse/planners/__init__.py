"""Planners: a global planner plus a local controller, every one registered in
:mod:`pathfuse.planners.registry` (global planners, controllers and the presets that
combine them; plug-ins through the entry-point group ``pathfuse.planners``).

* :mod:`~pathfuse.planners.global_planners` - the built-in global planners (A*, jump
  point search, A* smoothing, Theta*, Lazy Theta*, the visibility graph), registered
  by name, and :func:`~pathfuse.planners.global_planners.run_global`;
* :mod:`~pathfuse.planners.global_astar` - grid A* on the robot's c-space;
* :mod:`~pathfuse.planners.base` - the controller interface and the shared
  potential-field controller;
* :mod:`~pathfuse.planners.astar`, :mod:`~pathfuse.planners.apf`,
  :mod:`~pathfuse.planners.fusion`, :mod:`~pathfuse.planners.refs`,
  :mod:`~pathfuse.planners.dwa`, :mod:`~pathfuse.planners.mppi` - the controllers
  and their presets; :mod:`~pathfuse.planners.anyangle` - the presets of the path
  follower on the other global planners;
* :mod:`~pathfuse.planners.run` - running a planner offline or online.
"""

from pathfuse.planners.registry import (
    REGISTRY,
    PlannerSpec,
    controller_names,
    get_controller,
    get_global_planner,
    get_planner,
    global_planner_names,
    make_params,
    planner_names,
    register,
    register_controller,
    register_function,
    register_global_planner,
)

__all__ = ["REGISTRY", "PlannerSpec", "get_planner", "make_params", "planner_names", "register",
           "register_function", "register_global_planner", "get_global_planner",
           "global_planner_names", "register_controller", "get_controller",
           "controller_names"]
