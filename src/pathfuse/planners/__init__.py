"""Planners: a global planner plus a local controller, every one registered in
:mod:`pathfuse.planners.registry` (plug-ins through the entry-point group
``pathfuse.planners``).  The folder shows the split, as Nav2 splits its planner and
controller servers:

* :mod:`pathfuse.planners.globals` - the global planners: a problem in, a path out;
* :mod:`pathfuse.planners.controllers` - the controllers, each with its presets and kernel;
* here, what both sides and their callers share: the registry, the parameter groups
  (:mod:`~pathfuse.planners.params`), the controller interface
  (:mod:`~pathfuse.planners.base`, with :mod:`~pathfuse.planners.drive` and
  :mod:`~pathfuse.planners.recovery`, which its ``command`` runs) and
  :mod:`~pathfuse.planners.run`, which runs a global planner, then a controller.
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
