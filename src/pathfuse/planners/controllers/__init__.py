"""The controllers: from the global path (or without one) to the goal, offline or per tick.

Each module holds a controller (a :class:`~pathfuse.planners.base.Controller`), the
presets that pair it with a global planner, and its numba kernel where it has one:
:mod:`~pathfuse.planners.controllers.follow` (``astar``, ``astar-replan``),
:mod:`~pathfuse.planners.controllers.anyangle` (the follower on the other global
planners), :mod:`~pathfuse.planners.controllers.apf`,
:mod:`~pathfuse.planners.controllers.fusion` (+ ``fusion_window``),
:mod:`~pathfuse.planners.controllers.refs` (``ref6``, ``ref7``),
:mod:`~pathfuse.planners.controllers.dwa` (+ ``dwa_kernel``) and
:mod:`~pathfuse.planners.controllers.mppi` (+ ``mppi_kernel``).
:mod:`~pathfuse.planners.controllers.rpp` (Regulated Pure Pursuit, the followers on a
diff-drive robot) and :mod:`~pathfuse.planners.controllers.social` (the social critics)
are shared among them.
"""
