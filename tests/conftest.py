"""Shared test set-up: keep the planner registry as the library ships it.

Some tests register plug-in planners (directly, or by running an experiment
whose ``imports:`` registers one).  Each test gets the registry back as it
was before it ran, so no test sees another test's plug-ins.
"""

import pytest

from pathfuse.planners import registry


@pytest.fixture(autouse=True)
def _restore_planner_registry():
    registry.planner_names()  # make sure the built-in planners are loaded first
    saved = dict(registry.REGISTRY)
    saved_aliases = dict(registry._ALIASES)
    yield
    registry.REGISTRY.clear()
    registry.REGISTRY.update(saved)
    registry._ALIASES.clear()
    registry._ALIASES.update(saved_aliases)
    registry._DEFAULTS.clear()
