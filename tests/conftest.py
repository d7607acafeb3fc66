"""Shared test set-up: keep the planner registry as the library ships it.

Some tests register plug-in planners, global planners or controllers (directly,
or by running an experiment whose ``imports:`` registers one).  Each test gets the
registry back as it was before it ran, so no test sees another test's plug-ins.
"""

import pytest

from pathfuse.planners import registry


def _kept_registry():
    registry.planner_names()  # make sure the built-in planners are loaded first
    tables = (registry.REGISTRY, registry._ALIASES, registry.GLOBAL_PLANNERS,
              registry.CONTROLLERS)
    saved = [dict(t) for t in tables]
    yield
    for table, old in zip(tables, saved, strict=True):
        table.clear()
        table.update(old)
    registry._DEFAULTS.clear()


@pytest.fixture(autouse=True, scope="module")
def _restore_planner_registry_per_module():
    """A module-scoped fixture (a study run once for a module's tests) registers before
    any test's own snapshot is taken: the module's end restores the registry too."""
    yield from _kept_registry()


@pytest.fixture(autouse=True)
def _restore_planner_registry():
    yield from _kept_registry()
