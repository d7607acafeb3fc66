"""One DWA or MPPI tick stays bounded, and ``time_limit`` is checked before every tick.

``time.perf_counter`` is replaced by a clock that moves one second per reading, so the
deadline passes after a few readings whatever the machine's speed (no timed test).
"""

from __future__ import annotations

import itertools
import time

import pytest

import pathfuse
from pathfuse.planners.controllers.dwa import TICK_PIECES, DWAParams, check_tick_work
from pathfuse.result import Budget

ROWS = ["........", "..##....", "........", "....##..", "........"]


@pytest.mark.parametrize("planner", ["dwa", "mppi"])
def test_the_time_limit_is_checked_before_every_tick(planner, monkeypatch):
    g = pathfuse.GridMap.from_rows(ROWS)
    free = pathfuse.plan(g, (0.5, 0.5), (7.5, 4.5), planner)
    assert free.status.name == "SUCCESS" and free.iterations > 64  # longer than dwa's old batch
    clock = itertools.count(0.0, 1.0)
    monkeypatch.setattr(time, "perf_counter", lambda: next(clock))
    r = pathfuse.plan(g, (0.5, 0.5), (7.5, 4.5), planner, budget=Budget(time_limit_s=20.5))
    # about 9 readings before the first tick, at least one a tick: the deadline passes
    # within a dozen ticks; checked every 64 (dwa) or 16 (mppi) ticks it ran 64 or 16
    assert r.status.name == "TIMEOUT" and 0 < r.iterations < 16, (r.iterations, r.message)


def test_a_dwa_tick_within_the_budget_is_accepted():
    p = DWAParams(v_samples=64, w_samples=128, horizon_s=2.4, sim_step_s=0.02)
    assert 64 * 128 * 120 <= TICK_PIECES
    assert p.horizon_s == 2.4


@pytest.mark.parametrize("kw", [
    {"v_samples": 64, "w_samples": 128, "horizon_s": 10, "sim_step_s": 0.001},
    {"v_samples": 64, "w_samples": 128, "horizon_s": 2.5, "sim_step_s": 0.02},  # 125 pieces
    {"v_samples": 8, "w_samples": 16, "horizon_s": 10, "sim_step_s": 0.001},
])
def test_a_dwa_tick_over_the_budget_is_refused_naming_its_keys(kw):
    g = pathfuse.GridMap.from_rows(ROWS)
    with pytest.raises(pathfuse.ConfigError,
                       match=r"^dwa\.v_samples x w_samples x horizon_s / sim_step_s: must be "
                             r"at most 1000000 rollout pieces a tick, got "):
        pathfuse.plan(g, (0.5, 0.5), (7.5, 4.5), "dwa", **kw)


def test_the_budget_counts_pieces_as_the_kernel_does():
    check_tick_work(64, 125, 1.25, 0.01)  # 64 x 125 x 125 = 1,000,000: at the budget
    with pytest.raises(pathfuse.ConfigError, match="got 64 x 125 x 126 = 1008000$"):
        check_tick_work(64, 125, 1.2501, 0.01)
