"""Moving obstacles: a simulated world, scenario files and the episode runner.

* :mod:`pathfuse.world.scenario` - YAML scenarios (:func:`load_scenario`,
  :class:`Scenario`) and :mod:`pathfuse.world.generate` - seeded scenario families.
* :mod:`pathfuse.world.obstacles` - moving discs (constant velocity with
  bounces, patrols, seeded random walks).
* :mod:`pathfuse.world.world` - :class:`World` (``reset`` / ``step``) with exact
  continuous collision checks (:mod:`pathfuse.sweep`).
* :mod:`pathfuse.world.episode` - :func:`simulate` and :class:`Episode`: any
  registered planner, driven tick by tick.

>>> from pathfuse.world import simulate
>>> ep = simulate({"map": {"rows": ["......"]}, "start": [0.5, 0.5], "goal": [5.5, 0.5],
...                "robot": {"radius": 0.2}}, planner="fusion")
>>> ep.status.name
'SUCCESS'
"""

from pathfuse.world.episode import Episode, run_episode, simulate
from pathfuse.world.obstacles import LinearObstacle, PatrolObstacle, RandomWalkObstacle
from pathfuse.world.scenario import (
    PlannerChoice,
    Scenario,
    ScenarioError,
    load_scenario,
    save_scenario,
)
from pathfuse.world.world import Observation, SensedObstacles, World

__all__ = [
    "simulate",
    "run_episode",
    "Episode",
    "World",
    "Observation",
    "SensedObstacles",
    "Scenario",
    "PlannerChoice",
    "ScenarioError",
    "load_scenario",
    "save_scenario",
    "LinearObstacle",
    "PatrolObstacle",
    "RandomWalkObstacle",
]
