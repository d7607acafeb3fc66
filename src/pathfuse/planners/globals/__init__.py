"""The global planners: a problem in, a path of waypoints in metres out (or no path).

* :mod:`~pathfuse.planners.globals.astar` - grid A* on the robot's c-space and
  :class:`~pathfuse.planners.globals.astar.GlobalPlan`, what every global planner returns;
* :mod:`~pathfuse.planners.globals.builtin` - the built-in global planners (``astar``,
  ``jps``, ``astar-smooth``, ``thetastar``, ``lazy-thetastar``, ``shortest``),
  registered by name as a plug-in's are, and
  :func:`~pathfuse.planners.globals.builtin.run_global`, which runs any registered one.

Nothing here imports a controller: a controller follows whatever path it is given.
"""
