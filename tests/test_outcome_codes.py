"""One outcome vocabulary: the kernels' integer codes, the world's events and the
studies' outcome words all come from :class:`pathfuse.result.Status`."""

import numpy as np
import pytest

from pathfuse.field import kernels as fk
from pathfuse.result import (
    CODE_COLLISION,
    CODE_GROW,
    CODE_LOCAL_MINIMUM,
    CODE_MAX_ITERATIONS,
    CODE_NO_PATH,
    CODE_RUNNING,
    CODE_SUCCESS,
    CODE_TIMEOUT,
    Status,
    code_outcome,
    refined,
)


def test_codes_are_pinned():
    # numba caches a kernel by its own file: renumbering these needs the caches cleared
    assert [s.code for s in Status] == list(range(10))
    assert (CODE_SUCCESS, CODE_NO_PATH, CODE_LOCAL_MINIMUM, CODE_MAX_ITERATIONS,
            CODE_TIMEOUT, CODE_COLLISION, CODE_RUNNING, CODE_GROW) == (0, 1, 6, 7, 8, 9, -1, -2)


def test_every_code_maps_back_to_its_status():
    for s in Status:
        assert code_outcome(s.code) is s
        assert code_outcome(refined(s.code, 2)) is s
    assert code_outcome(CODE_RUNNING) is None
    assert code_outcome(CODE_GROW) is None
    with pytest.raises(ValueError, match="code: must be a kernel outcome code, got 42"):
        code_outcome(42)
    with pytest.raises(ValueError, match="code: must be a status code"):
        refined(CODE_RUNNING)


def test_field_loop_codes_are_distinct_and_derived():
    codes = [fk.CODE_RUNNING, fk.CODE_GOAL, fk.CODE_GOAL_SNAP, fk.CODE_STALLED,
             fk.CODE_BLOCKED, fk.CODE_COLLISION]
    assert len(set(codes)) == len(codes)
    assert fk.code_status(fk.CODE_GOAL, 3, 10) is Status.SUCCESS
    assert fk.code_status(fk.CODE_GOAL_SNAP, 3, 10) is Status.SUCCESS
    assert fk.code_status(fk.CODE_STALLED, 3, 10) is Status.LOCAL_MINIMUM
    assert fk.code_status(fk.CODE_BLOCKED, 3, 10) is Status.LOCAL_MINIMUM
    assert fk.code_status(fk.CODE_COLLISION, 3, 10) is Status.COLLISION
    assert fk.code_status(fk.CODE_RUNNING, 10, 10) is Status.MAX_ITERATIONS
    assert fk.code_status(fk.CODE_RUNNING, 3, 10) is Status.TIMEOUT


def test_keys_and_labels():
    assert Status.SUCCESS.key == "reached"
    assert [s.key for s in Status][1:] == [s.value for s in Status][1:]
    for s in Status:
        assert Status.from_key(s.key) is s
    with pytest.raises(ValueError, match="outcome: must be one of .*got 'arrived'"):
        Status.from_key("arrived")
    assert Status.LOCAL_MINIMUM.label == "local min"
    assert Status.START_OUT_OF_BOUNDS.label == "start out of bounds"


def test_costaware_search_returns_statuses():
    from pathfuse.search.costaware import costaware_search

    occ = np.zeros((3, 4), dtype=np.bool_)
    mult = np.ones(occ.shape)
    status, cells, _, _ = costaware_search(occ, mult, (0, 0), (2, 3))
    assert status is Status.SUCCESS and cells[-1].tolist() == [2, 3]
    occ[:, 2] = True
    assert costaware_search(occ, mult, (0, 0), (2, 3))[0] is Status.NO_PATH
    occ[:, 2] = False
    assert costaware_search(occ, mult, (0, 0), (2, 3), max_expansions=1)[0] \
        is Status.MAX_ITERATIONS
