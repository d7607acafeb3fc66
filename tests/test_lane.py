"""solve()'s one-call lane for the grid A* path follower (issue 21) against the layers it
writes out (run_global, plan_global, the controller's run_offline): the same results,
field by field, and the lane taken exactly where it applies."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pathfuse
import pathfuse.planners.run as run_mod
from pathfuse import Budget, ConfigError, GridMap, Status
from pathfuse.planners.controllers.follow import FollowController
from pathfuse.planners.registry import (
    PlannerSpec,
    get_global_planner,
    get_planner,
    register,
    register_global_planner,
)
from pathfuse.problem import Problem


def _maps() -> list[GridMap]:
    rng = np.random.default_rng(21)
    out = []
    for i, (h, w, p) in enumerate([(12, 17, 0.25), (20, 20, 0.35), (9, 30, 0.3)]):
        occ = rng.random((h, w)) < p
        if i == 2:
            occ[:, w // 2] = True  # two regions under either corner rule
        out.append(GridMap(occ, resolution=(1.0, 0.5, 0.25)[i], origin=((0.0, 0.0),
                                                                        (-3.0, 1.5),
                                                                        (2.0, -1.0))[i]))
    return out


def _queries(g: GridMap, n: int, seed: int) -> list[tuple[tuple[float, float], ...]]:
    rng = np.random.default_rng(seed)
    free = np.argwhere(~g.occupied)
    (ox, oy), res = g.origin, g.resolution
    out = []
    for _ in range(n):
        a, b = free[rng.integers(len(free))], free[rng.integers(len(free))]
        ja, jb = rng.random(2), rng.random(2)  # anywhere inside the cells, not only centres
        # plain floats, as plan()'s quick path takes them
        out.append(((float(ox + (a[1] + ja[0]) * res), float(oy + (a[0] + ja[1]) * res)),
                    (float(ox + (b[1] + jb[0]) * res), float(oy + (b[0] + jb[1]) * res))))
    out.append((out[0][0], out[0][0]))  # start == goal
    return out


def _same(a: pathfuse.PlanResult, b: pathfuse.PlanResult) -> None:
    assert a.status is b.status
    assert a.planner == b.planner and a.message == b.message
    assert a.expansions == b.expansions and a.iterations == b.iterations
    assert a.length == b.length or (math.isnan(a.length) and math.isnan(b.length))
    assert a.path.dtype == b.path.dtype and np.array_equal(a.path, b.path)
    assert type(a.info) is type(b.info) and list(a.info) == list(b.info)
    for k, v in a.info.items():
        w = b.info[k]
        if k.endswith("time_s") or k.endswith("_per_s"):  # clocks
            continue
        if isinstance(v, np.ndarray):
            assert v.dtype == w.dtype and np.array_equal(v, w), k
        else:
            assert type(v) is type(w) and v == w, k
    if a.status is Status.SUCCESS:
        assert a.info["min_clearance_m"] == b.info["min_clearance_m"]


def _both(monkeypatch, *args, **kw):
    calls = []
    lane = run_mod._lane  # the body of solve()'s lane and of plan()'s quick_plan

    def counted(*a, **k):
        calls.append(1)
        return lane(*a, **k)

    monkeypatch.setattr(run_mod, "_lane", counted)
    fast = pathfuse.plan(*args, **kw)
    again = pathfuse.plan(*args, **kw)  # after the first: plan()'s quick_plan, where it applies
    monkeypatch.setattr(run_mod, "_LANE", False)
    slow = pathfuse.plan(*args, **kw)
    slow2 = pathfuse.plan(*args, **kw)  # _same adds min_clearance_m to both infos it reads
    monkeypatch.setattr(run_mod, "_LANE", True)
    _same(fast, slow)
    _same(again, slow2)
    assert len(calls) in (0, 2)  # both plans took the lane, or neither
    return fast, len(calls) // 2


@pytest.mark.parametrize("planner", ["astar", "astar-replan", "astar-follow"])
@pytest.mark.parametrize("heuristic", ["euclidean", "octile"])
@pytest.mark.parametrize("corner_cutting", [False, True])
def test_lane_equals_layers(monkeypatch, planner, heuristic, corner_cutting):
    params = {"heuristic": heuristic}
    if planner != "astar-replan":
        params["corner_cutting"] = corner_cutting
    elif corner_cutting:
        pytest.skip("astar-replan has no corner rule")
    statuses = set()
    for i, g in enumerate(_maps()):
        for s, t in _queries(g, 25, i):
            r, taken = _both(monkeypatch, g, s, t, planner, **params)
            assert taken == 1
            statuses.add(r.status)
            r, taken = _both(monkeypatch, g, s, t, planner, budget=Budget(max_iterations=3),
                             **params)
            assert taken == 1
            statuses.add(r.status)
    # the maps are cut into regions: every outcome of a search is compared
    assert {Status.SUCCESS, Status.NO_PATH, Status.MAX_ITERATIONS} <= statuses


def test_lane_timeout_and_blocked_ends(monkeypatch):
    g = _maps()[1]
    s, t = _queries(g, 1, 5)[0]
    r, taken = _both(monkeypatch, g, s, t, budget=Budget(time_limit_s=1e-300))
    assert taken == 1 and r.status in (Status.TIMEOUT, Status.SUCCESS)
    blocked = tuple(float(v) for v in g.cell_to_world([np.argwhere(g.occupied)[0]])[0])
    r, taken = _both(monkeypatch, g, blocked, t)
    assert taken == 0 and r.status is Status.START_OCCUPIED


def test_lane_not_taken_where_it_does_not_apply(monkeypatch):
    g = GridMap.from_rows(["......", "..#...", "..#...", "......"], resolution=0.5)
    s, t = (0.25, 0.25), (2.75, 1.75)
    # a disc robot, a margin, another global planner, another controller: the layers
    for kw in ({"robot_radius_m": 0.1}, {"clearance_m": 0.1}, {"global_planner": "jps"},
               {"planner": "fusion"}, {"planner": "thetastar"}):
        _, taken = _both(monkeypatch, g, s, t, **kw)
        assert taken == 0, kw


def test_lane_not_taken_for_an_own_run_or_a_plugin_astar(monkeypatch):
    g = GridMap.from_rows(["....", ".##.", "...."])

    class Mine(FollowController):
        name = "mine-follow"

        def run(self, deadline):
            out = super().run(deadline)
            out.message = "mine"
            return out

    base = get_planner("astar")
    register(PlannerSpec("mine", base.params_cls, "a follower with a run of its own",
                         controller=Mine, global_planner="astar"))
    r, taken = _both(monkeypatch, g, (0.5, 0.5), (3.5, 2.5), "mine")
    assert taken == 0 and r.message == "mine"
    builtin = get_global_planner("astar")
    register_global_planner("astar", lambda pb: np.array([pb.start, pb.goal]), "a plug-in")
    r, taken = _both(monkeypatch, g, (0.5, 0.5), (3.5, 2.5))
    assert taken == 0 and r.length == pytest.approx(math.hypot(3, 2))
    register_global_planner("astar", builtin.func, builtin.description, warmup=builtin.warmup,
                            kernels=builtin.kernels, taut=builtin.taut)
    _, taken = _both(monkeypatch, g, (0.5, 0.5), (3.5, 2.5))
    assert taken == 1


def test_lane_bad_heuristic_is_the_layers_error(monkeypatch):
    g = GridMap.from_rows(["....", ".##.", "...."])
    spec = get_planner("astar")
    from pathfuse.problem import Problem

    pb = Problem.create(g, (0.5, 0.5), (3.5, 2.5))

    class P:
        heuristic = "manhattan"
        corner_cutting = False

    with pytest.raises(ConfigError) as fast:
        run_mod.solve(spec, pb, P())
    monkeypatch.setattr(run_mod, "_LANE", False)
    with pytest.raises(ConfigError) as slow:
        run_mod.solve(spec, pb, P())
    assert str(fast.value) == str(slow.value)


@pytest.mark.parametrize("radius", [0.0, 0.3])
def test_solve_reports_the_problems_failure(radius):
    # whatever the lane, a start or goal outside the map or blocked (for a point or a disc
    # robot) ends plan() with failure()'s status and message
    g = GridMap.from_rows(["....#", ".#...", "....."])
    points = [(0.5, 0.5), (4.5, 2.5), (1.5, 1.5), (4.5, 2.9), (-0.5, 1.0), (2.0, 3.5),
              (5.2, 0.5), (1.0, 0.99), (0.1, 2.9)]
    seen = set()
    for s in points:
        for e in points:
            bad = Problem.create(g, s, e, radius).failure()
            r = pathfuse.plan(g, s, e, robot_radius_m=radius)
            if bad is None:
                assert r.status.name not in ("START_OUT_OF_BOUNDS", "GOAL_OUT_OF_BOUNDS",
                                             "START_OCCUPIED", "GOAL_OCCUPIED")
            else:
                assert (r.status, r.message) == bad
            seen.add(r.status.name)
    assert {"SUCCESS", "START_OUT_OF_BOUNDS", "GOAL_OUT_OF_BOUNDS", "START_OCCUPIED",
            "GOAL_OCCUPIED"} <= seen


def test_quick_plan_taken_only_where_nothing_is_left_to_check(monkeypatch):
    g = GridMap.from_rows(["......", "..#...", "..#...", "......"], resolution=0.5,
                          origin=(1.0, -2.0))
    spec = get_planner("astar")
    from pathfuse.planners.registry import make_params

    cfg = make_params(spec, None)
    s, t = (1.25, -1.75), (3.75, -0.25)
    pathfuse.plan(g, s, t)  # solve() took the lane: remembered
    quick = run_mod.quick_plan(spec, cfg, g, s, t, None)
    assert quick is not None
    _same(quick, pathfuse.plan(g, s, t, robot_radius_m=0.0))  # through solve()
    # anything plan() must check, or an outcome other than a search's: None
    for bad in ((float("nan"), -1.75), (1, -1.75), [1.25, -1.75], (1.25,), (0.0, -1.75),
                (2.25, -1.25), np.array([1.25, -1.75])):
        assert run_mod.quick_plan(spec, cfg, g, bad, t, None) is None, bad
        assert run_mod.quick_plan(spec, cfg, g, s, bad, None) is None, bad
    assert run_mod.quick_plan(spec, cfg, g, s, t, "budget") is None
    assert run_mod.quick_plan(spec, cfg, g.occupied, s, t, None) is None
    other = make_params(spec, {"heuristic": "octile", "lookahead_time_s": 1.2345})
    assert run_mod.quick_plan(spec, other, g, s, t, None) is None  # not planned with yet
    pathfuse.plan(g, s, t, heuristic="octile", lookahead_time_s=1.2345)
    assert run_mod.quick_plan(spec, other, g, s, t, None) is not None
    monkeypatch.setattr(run_mod, "_LANE", False)
    assert run_mod.quick_plan(spec, cfg, g, s, t, None) is None


@pytest.mark.parametrize("start, error, words", [
    ((float("nan"), 0.5), "QueryError", "start"),
    ((0.5, float("inf")), "QueryError", "start"),
    (("a", 0.5), "QueryError", "start"),
    ((0.5,), "QueryError", "start"),
])
def test_plan_checks_bad_input_after_warm_paths(start, error, words):
    g = GridMap.from_rows(["....", ".##.", "...."])
    pathfuse.plan(g, (0.5, 0.5), (3.5, 2.5))  # the quick path is open for these parameters
    with pytest.raises(getattr(pathfuse, error)) as e:
        pathfuse.plan(g, start, (3.5, 2.5))
    assert words in str(e.value)
    with pytest.raises(getattr(pathfuse, error)) as e:
        pathfuse.plan(g, (3.5, 2.5), start)
    assert "goal" in str(e.value)
    with pytest.raises(pathfuse.QueryError, match="grid"):
        pathfuse.plan(g.occupied, (0.5, 0.5), (3.5, 2.5))
    with pytest.raises(ConfigError, match="budget"):
        pathfuse.plan(g, (0.5, 0.5), (3.5, 2.5), budget=5)
    with pytest.raises(ConfigError, match="clearance_m"):
        pathfuse.plan(g, (0.5, 0.5), (3.5, 2.5), clearance_m=float("nan"))


def test_found_path_result_is_a_plan_result():
    import copy
    import dataclasses
    import pickle

    from pathfuse.planners.globals.astar import found_message

    g = GridMap.from_rows(["......", "..#...", "..#...", "......"], resolution=0.5)
    r = pathfuse.plan(g, (0.25, 0.25), (2.75, 1.75))
    assert isinstance(r, pathfuse.PlanResult) and r
    assert "message" not in r.__dict__  # written on first read
    text = found_message(len(r.info["cells"]), r.length, r.expansions)
    assert r.message == text and r.__dict__["message"] == text
    assert repr(r).startswith("PlanResult(status=<Status.SUCCESS")
    assert dataclasses.asdict(r)["message"] == text
    assert r.to_dict()["message"] == text
    fresh = pathfuse.plan(g, (0.25, 0.25), (2.75, 1.75))
    for back in (pickle.loads(pickle.dumps(fresh)), copy.copy(fresh),
                 dataclasses.replace(fresh, planner="other")):
        assert isinstance(back, pathfuse.PlanResult) and back.message == text
        assert np.array_equal(back.path, r.path) and back.length == r.length
    assert type(pickle.loads(pickle.dumps(fresh))) is pathfuse.PlanResult
    assert dataclasses.replace(fresh, planner="other").planner == "other"
    with pytest.raises(dataclasses.FrozenInstanceError):
        fresh.message = "x"  # type: ignore[misc]
