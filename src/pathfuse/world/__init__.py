"""Moving obstacles: a simulated world, scenario files, online planners and the episode runner.

* :mod:`pathfuse.world.scenario` - YAML scenarios (:func:`load_scenario`,
  :class:`Scenario`) and :mod:`pathfuse.world.generate` - seeded scenario families.
* :mod:`pathfuse.world.obstacles` - moving discs (constant velocity with
  bounces, patrols, seeded random walks).
* :mod:`pathfuse.world.world` - :class:`World` (``reset`` / ``step``) with exact
  continuous collision checks (:mod:`pathfuse.world.geometry`).
* :mod:`pathfuse.world.online` - the online planners and their registry.
* :mod:`pathfuse.world.episode` - :func:`simulate` and :class:`Episode`.

>>> from pathfuse.world import simulate
>>> ep = simulate({"map": {"rows": ["......"]}, "start": [0.5, 0.5], "goal": [5.5, 0.5],
...                "robot": {"radius": 0.2}}, planner="fusion")
>>> ep.status.name
'REACHED'
"""

from pathfuse.world.episode import Episode, EpisodeStatus, run_episode, simulate
from pathfuse.world.obstacles import LinearObstacle, PatrolObstacle, RandomWalkObstacle
from pathfuse.world.online import (
    ONLINE_REGISTRY,
    OnlinePlanner,
    OnlinePlannerSpec,
    PlannerContext,
    get_online_planner,
    online_planner_names,
    register_online,
)
from pathfuse.world.scenario import (
    PlannerChoice,
    RobotSpec,
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
    "EpisodeStatus",
    "World",
    "Observation",
    "SensedObstacles",
    "Scenario",
    "RobotSpec",
    "PlannerChoice",
    "ScenarioError",
    "load_scenario",
    "save_scenario",
    "LinearObstacle",
    "PatrolObstacle",
    "RandomWalkObstacle",
    "ONLINE_REGISTRY",
    "OnlinePlanner",
    "OnlinePlannerSpec",
    "PlannerContext",
    "get_online_planner",
    "online_planner_names",
    "register_online",
]
