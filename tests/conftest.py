"""Shared test set-up: keep the planner registries as the library ships them.

Some tests register plug-in planners (directly, or by running an experiment
whose ``imports:`` registers one).  Each test gets the registries back as they
were before it ran, so no test sees another test's plug-ins.
"""

import pytest

from pathfuse.planners import registry
from pathfuse.world import online


@pytest.fixture(autouse=True)
def _restore_planner_registries():
    registry.planner_names()  # make sure the built-in planners are loaded first
    online.online_planner_names()
    saved = dict(registry.REGISTRY)
    saved_online = dict(online.ONLINE_REGISTRY)
    yield
    registry.REGISTRY.clear()
    registry.REGISTRY.update(saved)
    online.ONLINE_REGISTRY.clear()
    online.ONLINE_REGISTRY.update(saved_online)
