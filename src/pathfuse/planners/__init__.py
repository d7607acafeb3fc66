"""Planners: a global planner plus a local controller, every one registered in
:mod:`pathfuse.planners.registry` (global planners, controllers and the presets that
combine them; plug-ins through the entry-point group ``pathfuse.planners``).

The folder shows the split (as Nav2 splits its planner and controller servers):

* :mod:`pathfuse.planners.globals` - the global planners, a problem in and a path out:
  :mod:`~pathfuse.planners.globals.astar` (grid A* on the robot's c-space,
  ``GlobalPlan``) and :mod:`~pathfuse.planners.globals.builtin` (the built-in global
  planners registered by name, :func:`~pathfuse.planners.globals.builtin.run_global`);
* :mod:`pathfuse.planners.controllers` - the controllers, each module with its presets
  (``astar`` in :mod:`~pathfuse.planners.controllers.follow`, ``fusion``, ``dwa``, ...)
  and its numba kernel, and what only controllers share (Regulated Pure Pursuit, the
  social critics);
* at this level, what both sides and the callers share: the registry, the parameter
  groups (:mod:`~pathfuse.planners.params`), the controller interface
  (:mod:`~pathfuse.planners.base`, with :mod:`~pathfuse.planners.drive` and
  :mod:`~pathfuse.planners.recovery`, which its ``command`` runs) and
  :mod:`~pathfuse.planners.run`, which runs a global planner and then a controller,
  offline or online.
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
