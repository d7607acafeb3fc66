"""Sweeps: what is stored, parallel == serial, errors, crashed workers, kill -9 and resume.

The engine tests use a planner of their own (a plain-Python Dijkstra written
here, loaded through the experiment's ``imports``), so they test the sweep
machinery independently of pathfuse's planners; it can also sleep, raise or
kill its worker process on a chosen seed.
"""

from __future__ import annotations

import io
import json
import math
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from pathfuse.bench import ResultStore, SweepInterrupted, comparable_rows, run_bench
from pathfuse.bench.runner import make_batches
from pathfuse.generate import PAPER_GOAL, PAPER_START, paper_map
from pathfuse.result import ConfigError

MOVINGAI = Path(__file__).resolve().parent / "data" / "movingai"

PLUGIN = '''
"""A test planner: 8-connected Dijkstra without corner cutting, in plain Python."""
import heapq, math, os, time
from dataclasses import dataclass
import numpy as np
from pathfuse.planners.registry import register_function
from pathfuse.result import PlanResult, Status, path_length


@dataclass(frozen=True)
class Params:
    sleep_s: float = 0.0
    crash_seed: int = -1
    raise_seed: int = -1
    seed: int = 0


def dijkstra_cells(occ, s, g):
    H, W = occ.shape
    dist, prev, pq, n = {s: 0.0}, {}, [(0.0, s)], 0
    while pq:
        d, u = heapq.heappop(pq)
        if d > dist[u]:
            continue
        n += 1
        if u == g:
            break
        r, c = u
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                rr, cc = r + dr, c + dc
                if (not dr and not dc) or not (0 <= rr < H and 0 <= cc < W) or occ[rr, cc]:
                    continue
                if dr and dc and (occ[r + dr, c] or occ[r, c + dc]):
                    continue
                nd = d + (math.sqrt(2.0) if dr and dc else 1.0)
                if nd < dist.get((rr, cc), math.inf):
                    dist[(rr, cc)] = nd
                    prev[(rr, cc)] = u
                    heapq.heappush(pq, (nd, (rr, cc)))
    if g not in dist:
        return None, n
    cells = [g]
    while cells[-1] != s:
        cells.append(prev[cells[-1]])
    return cells[::-1], n


def plan(grid, start, goal, params, budget):
    if params.seed == params.crash_seed:
        os._exit(3)
    if params.seed == params.raise_seed:
        raise RuntimeError(f"boom on seed {params.seed}")
    t0 = time.perf_counter()
    if params.sleep_s:
        time.sleep(params.sleep_s)
    s = tuple(int(v) for v in grid.world_to_cell(start)[0])
    g = tuple(int(v) for v in grid.world_to_cell(goal)[0])
    cells, n = dijkstra_cells(grid.occupied, s, g)
    if cells is None:
        return PlanResult(Status.NO_PATH, time_s=time.perf_counter() - t0, expansions=n,
                          message="no path")
    path = grid.cell_to_world(np.array(cells))
    return PlanResult(Status.SUCCESS, path=path, length=path_length(path),
                      time_s=time.perf_counter() - t0, expansions=n,
                      info={"cells": len(cells), "search_time_s": time.perf_counter() - t0})


register_function("tdij", plan, Params, "test Dijkstra")
'''


def make_study(tmp_path: Path, body: str, name: str = "exp.yaml") -> Path:
    (tmp_path / "tplug.py").write_text(PLUGIN)
    p = tmp_path / name
    p.write_text("imports: [tplug.py]\nreference: tdij\n" + body)
    return p


PAPER = """
name: paper-study
seeds: %d
maps:
  - name: paper
    map: paper
  - name: tiny
    map: {rows: ["........", ".####...", ".#..#.#.", ".####..."]}
    queries: [{start: [0.5, 0.5], goal: [7.5, 3.5]}, {start: [0.5, 3.5], goal: [7.5, 0.5]},
              {start: [0.5, 0.5], goal: [2.5, 1.5]}]
planners:
  - tdij
  - name: tdij
    label: slow
    params: {sleep_s: [0.0001, 0.0002]%s}
"""


def paper_study(tmp_path: Path, seeds: int = 4, extra: str = "", name: str = "exp.yaml"):
    return make_study(tmp_path, PAPER % (seeds, extra), name)


def test_serial_sweep_stores_what_the_planner_returns(tmp_path):
    import importlib.util

    exp = paper_study(tmp_path, seeds=3)
    s = run_bench(exp, tmp_path / "a.db", workers=1, progress=False)
    n = 3 * (1 + 3) * 3  # seeds x (paper + 3 tiny queries) x configs
    assert (s.total, s.ran, s.skipped, s.errors) == (n, n, 0, 0)
    assert s.complete and s.failed == 3 * 3 and s.succeeded == n - s.failed
    spec = importlib.util.spec_from_file_location("tplug_check", tmp_path / "tplug.py")
    plug = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(plug)
    with ResultStore(tmp_path / "a.db", readonly=True) as st:
        rows = st.results()
    assert len(rows) == n
    for r in rows:
        params = json.loads(r["params"])
        assert params["seed"] == r["seed"] and params["planner"] == r["planner"] == "tdij"
        assert r["pathfuse_version"] and r["host"] and r["time"] >= 0
        if r["map_name"] == "paper":
            g = paper_map(r["seed"])
            assert (r["start_x"], r["start_y"]) == PAPER_START
            assert (r["goal_x"], r["goal_y"]) == PAPER_GOAL
        else:
            from pathfuse.grid import GridMap

            g = GridMap.from_rows(["........", ".####...", ".#..#.#.", ".####..."])
        s_cell = tuple(int(v) for v in g.world_to_cell([r["start_x"], r["start_y"]])[0])
        g_cell = tuple(int(v) for v in g.world_to_cell([r["goal_x"], r["goal_y"]])[0])
        cells, _ = plug.dijkstra_cells(g.occupied, s_cell, g_cell)
        if cells is None:
            assert r["status_name"] == "NO_PATH" and not r["solved"]
            assert r["solution_length"] is None
            continue
        expect = float(np.hypot(*np.diff(np.array(cells, float), axis=0).T).sum())
        assert r["status_name"] == "SUCCESS" and r["solved"] == 1
        assert r["solution_length"] == pytest.approx(expect, abs=1e-9)
        assert r["solution_segments"] == len(cells) - 1
        # the reference is the same Dijkstra: R_length is exactly 0
        assert r["reference_length"] == pytest.approx(expect) and r["R_length"] == 0.0
        assert r["reference_source"] == "tdij"
        assert json.loads(r["info"]) == {"cells": len(cells)}  # clock readings split off
        assert "search_time_s" in json.loads(r["timing"])
    configs = {r["config"] for r in rows}
    assert configs == {"tdij", "slow(sleep_s=0.0001)", "slow(sleep_s=0.0002)"}
    exps = {r["experiment"] for r in rows}
    assert exps == {"paper-study/paper", "paper-study/tiny"}


def test_parallel_and_batched_runs_equal_the_serial_run(tmp_path):
    exp = paper_study(tmp_path, seeds=5)
    run_bench(exp, tmp_path / "serial.db", workers=1, progress=False)
    s2 = run_bench(exp, tmp_path / "par.db", workers=2, progress=False, batch_size=4)
    assert s2.ran == s2.total and s2.errors == 0
    a, b = comparable_rows(tmp_path / "serial.db"), comparable_rows(tmp_path / "par.db")
    assert len(a) == s2.total and a == b


def test_resume_runs_only_what_is_missing(tmp_path):
    exp = paper_study(tmp_path, seeds=6)
    db = tmp_path / "r.db"
    first = run_bench(exp, db, seeds="0:3", workers=1, progress=False)
    again = run_bench(exp, db, seeds="0:3", workers=1, progress=False)
    assert again.ran == 0 and again.skipped == first.total
    full = run_bench(exp, db, workers=2, progress=False)
    assert full.skipped == first.total and full.ran == full.total - first.total
    run_bench(exp, tmp_path / "once.db", workers=1, progress=False)
    assert comparable_rows(db) == comparable_rows(tmp_path / "once.db")
    with sqlite3.connect(db) as c:
        sessions = c.execute("SELECT state, planned, skipped, ran FROM pathfuse_sessions "
                             "ORDER BY id").fetchall()
    assert sessions == [("finished", first.total, 0, first.total),
                        ("finished", first.total, first.total, 0),
                        ("finished", full.total, first.total, full.ran)]


def test_a_run_that_raises_is_stored_and_the_sweep_goes_on(tmp_path):
    exp = paper_study(tmp_path, seeds=4, extra=", raise_seed: 2")
    db = tmp_path / "e.db"
    s = run_bench(exp, db, workers=2, progress=False)
    assert s.complete and s.errors == 2 * 4  # 2 slow configs x (paper + 3 queries) on seed 2
    with ResultStore(db, readonly=True) as st:
        bad = st.results("status_name = 'ERROR'")
        good = st.results("status_name != 'ERROR'")
    assert {r["seed"] for r in bad} == {2} and all(r["config"] != "tdij" for r in bad)
    assert all(r["error"] == "RuntimeError: boom on seed 2" for r in bad)
    assert all("Traceback" in r["traceback"] and r["status_text"] == "Crash"  # OMPL's text
               and r["status"] == 7 for r in bad)
    assert len(good) == s.total - s.errors
    # errors count as stored; retry_errors runs them again (and they fail again)
    assert run_bench(exp, db, workers=1, progress=False).ran == 0
    retry = run_bench(exp, db, workers=1, progress=False, retry_errors=True)
    assert retry.ran == s.errors and retry.errors == s.errors
    with ResultStore(db, readonly=True) as st:
        assert st.count() == s.total


def test_a_crashing_worker_costs_only_its_run(tmp_path):
    exp = paper_study(tmp_path, seeds=4, extra=", crash_seed: 1")
    db = tmp_path / "c.db"
    s = run_bench(exp, db, workers=2, progress=False, batch_size=5)
    assert s.complete and s.crashed == s.errors == 2 * 4
    with ResultStore(db, readonly=True) as st:
        bad = st.results("status_name = 'ERROR'")
        assert {r["seed"] for r in bad} == {1}
        assert all(r["error"].startswith("WorkerCrashed") for r in bad)
        assert st.count() == s.total
    # every other run equals a sweep that never crashed
    ok = paper_study(tmp_path, seeds=4, name="ok.yaml")
    run_bench(ok, tmp_path / "ok.db", workers=1, progress=False)
    cols = ("map_name", "seed", "query_index", "config_name", "status_name",
            "solution_length", "solution_clearance", "expansions", "R_length", "metrics")
    good = {tuple(r[c] for c in cols) for r in comparable_rows(db).values()
            if r["status_name"] != "ERROR"}
    ref = {tuple(r[c] for c in cols) for r in comparable_rows(tmp_path / "ok.db").values()}
    assert good <= ref and len(good) == s.total - s.errors


def _count(db: Path) -> int:
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=5) as c:
            return int(c.execute("SELECT COUNT(*) FROM runs").fetchone()[0])
    except sqlite3.Error:
        return 0


def _start_sweep(exp: Path, db: Path, workers: int) -> subprocess.Popen:
    code = ("import sys; from pathfuse.bench import run_bench; "
            f"run_bench({str(exp)!r}, {str(db)!r}, workers={workers}, progress=False)")
    return subprocess.Popen([sys.executable, "-c", code], start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


def _wait_for_runs(proc: subprocess.Popen, db: Path, n: int, timeout: float = 60) -> int:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        k = _count(db)
        if k >= n or proc.poll() is not None:
            return k
        time.sleep(0.01)
    raise AssertionError(f"no {n} runs stored after {timeout} s")


def _reap(proc: subprocess.Popen) -> None:
    """Kill what is left of the process group this test started (pool workers)."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait(timeout=30)


SLOW = """
name: slow
seeds: 24
maps: [paper]
planners:
  - name: tdij
    params: {sleep_s: [0.03, 0.031]}
"""


@pytest.mark.slow
def test_kill_9_then_resume_equals_an_uninterrupted_sweep(tmp_path):
    exp = make_study(tmp_path, SLOW)
    db = tmp_path / "k.db"
    proc = _start_sweep(exp, db, workers=2)
    try:
        stored = _wait_for_runs(proc, db, 8)
        assert proc.poll() is None, proc.stderr.read().decode()
        os.kill(proc.pid, signal.SIGKILL)  # the client dies without any cleanup
        proc.wait(timeout=30)
    finally:
        _reap(proc)
    with sqlite3.connect(db) as c:
        assert c.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        at_kill = c.execute("SELECT COUNT(*) FROM runs").fetchone()[0]
        state = c.execute("SELECT state FROM pathfuse_sessions").fetchone()[0]
    assert stored <= at_kill < 48 and state == "running"
    resumed = run_bench(exp, db, workers=2, progress=False)
    assert resumed.skipped == at_kill and resumed.ran == 48 - at_kill
    run_bench(exp, tmp_path / "whole.db", workers=2, progress=False)
    a, b = comparable_rows(db), comparable_rows(tmp_path / "whole.db")
    assert len(a) == 48 and a == b


@pytest.mark.slow
def test_ctrl_c_stops_cleanly_and_resumes(tmp_path):
    exp = make_study(tmp_path, SLOW)
    db = tmp_path / "i.db"
    proc = _start_sweep(exp, db, workers=1)
    try:
        _wait_for_runs(proc, db, 4)
        assert proc.poll() is None
        os.kill(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    finally:
        _reap(proc)
    assert b"SweepInterrupted" in err or b"KeyboardInterrupt" in err
    with sqlite3.connect(db) as c:
        state, ran = c.execute("SELECT state, ran FROM pathfuse_sessions").fetchone()
        stored = c.execute("SELECT COUNT(*) FROM runs").fetchone()[0]
    assert state == "interrupted" and ran == stored and 4 <= stored < 48
    assert run_bench(exp, db, workers=2, progress=False).ran == 48 - stored


def test_interrupt_in_process_raises_with_a_summary(tmp_path):
    exp = make_study(tmp_path, SLOW.replace("seeds: 24", "seeds: 3"))

    def interrupt(total, todo):  # Ctrl-C as soon as the sweep starts
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_bench(exp, tmp_path / "x.db", workers=1, progress=False, on_start=interrupt)
    calls = []

    def late(total, todo):
        calls.append((total, todo))
        signal.setitimer(signal.ITIMER_REAL, 0.1)

    old = signal.signal(signal.SIGALRM, lambda *a: (_ for _ in ()).throw(KeyboardInterrupt))
    try:
        with pytest.raises(SweepInterrupted) as ei:
            run_bench(exp, tmp_path / "y.db", workers=1, progress=False, on_start=late)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    summ = ei.value.summary
    assert summ.interrupted and not summ.complete and calls == [(6, 6)]
    assert "run the same command again" in str(summ)
    with ResultStore(tmp_path / "y.db", readonly=True) as st:
        assert st.count() == summ.ran


def test_progress_display_is_a_few_lines_off_a_terminal(tmp_path):
    exp = paper_study(tmp_path, seeds=1)
    out = io.StringIO()
    s = run_bench(exp, tmp_path / "p.db", workers=1, progress=True, stream=out)
    lines = out.getvalue().strip().splitlines()
    assert len(lines) == 1, lines  # a short sweep off a terminal: its last line only
    assert lines[0].startswith("paper-study [") and f"{s.total}/{s.total} 100%" in lines[0]
    assert "runs/s" in lines[0] and " in 0:00:" in lines[0] and "\r" not in lines[0]
    quiet = io.StringIO()
    run_bench(exp, tmp_path / "q.db", workers=1, progress=False, stream=quiet)
    assert quiet.getvalue() == ""
    auto = io.StringIO()  # None: the same display (a terminal would get a live bar)
    run_bench(exp, tmp_path / "r.db", workers=1, progress=None, stream=auto)
    assert auto.getvalue().splitlines()[-1].startswith("paper-study [")
    nothing = io.StringIO()  # resumed with nothing left: no bar, the summary says it
    again = run_bench(exp, tmp_path / "r.db", workers=1, progress=None, stream=nothing)
    assert nothing.getvalue() == "" and again.ran == 0
    assert str(again).startswith("paper-study: nothing to run, all")


def test_bad_arguments_are_config_errors(tmp_path):
    exp = paper_study(tmp_path, seeds=1)
    db = tmp_path / "never.db"
    for kw, msg in ((dict(workers=0), "workers: must be an integer >= 1"),
                    (dict(workers=1.5), "workers: must be an integer >= 1"),
                    (dict(scheduler="localhost:8786"), "scheduler: must be an address"),
                    (dict(batch_size=0), "batch_size: must be an integer >= 1"),
                    (dict(seeds="x"), "seeds (override): must be")):
        with pytest.raises(ConfigError, match=msg.replace("(", r"\(").replace(")", r"\)")):
            run_bench(exp, db, progress=False, **kw)
    assert not db.exists()
    with pytest.raises(ConfigError, match="no such experiment file"):
        run_bench(tmp_path / "nope.yaml", db)
    with pytest.raises(ConfigError, match="folder .* does not exist"):
        run_bench(exp, tmp_path / "no" / "x.db", progress=False)


def test_random_queries_are_free_far_apart_and_reproducible(tmp_path):
    exp = make_study(tmp_path, """
seeds: 3
maps:
  - name: r
    map: {random: {size: [30, 20], density: 0.25}}
    queries: {random: 4, min_distance_m: 8}
planners: [tdij]
""")
    run_bench(exp, tmp_path / "a.db", workers=1, progress=False)
    run_bench(exp, tmp_path / "b.db", workers=2, progress=False, batch_size=2)
    a = comparable_rows(tmp_path / "a.db")
    assert a == comparable_rows(tmp_path / "b.db") and len(a) == 12
    from pathfuse.io import map_from_spec

    pairs = set()
    for r in a.values():
        g = map_from_spec({"random": {"size": [30, 20], "density": 0.25, "seed": r["seed"]}})
        pts = np.array([[r["start_x"], r["start_y"]], [r["goal_x"], r["goal_y"]]])
        assert g.is_free(pts).all()
        assert math.dist(pts[0], pts[1]) >= 8
        assert r["status_name"] == "SUCCESS"  # drawn in one free region
        pairs.add(tuple(pts.ravel()))
    assert len(pairs) == 12


def test_robot_radius_plans_on_the_inflated_map(tmp_path):
    body = """
seeds: 1
robot_radius_m: %s
maps:
  - name: gap
    map: {rows: ["#########", "....#....", ".........", "....#....", "#########"]}
    start: [0.5, 2.5]
    goal: [8.5, 2.5]
planners: [tdij]
"""
    s0 = run_bench(make_study(tmp_path, body % 0.0, "a.yaml"), tmp_path / "a.db",
                   workers=1, progress=False)
    s1 = run_bench(make_study(tmp_path, body % 0.6, "b.yaml"), tmp_path / "b.db",
                   workers=1, progress=False)
    assert s0.succeeded == 1
    # a 1.2 m wide robot cannot pass the one-cell gap
    assert s1.failed == 1 and s1.succeeded == 0


@pytest.mark.skipif(not (MOVINGAI / "den312d.map").is_file(), reason="test data missing")
def test_scen_optimal_lengths_are_the_reference(tmp_path):
    exp = make_study(tmp_path, f"""
seeds: [0]
reference: null
maps:
  - name: den312d
    map: {{movingai: {MOVINGAI / 'den312d.map'}}}
    scen: {MOVINGAI / 'den312d.map.scen'}
    lines: {{every: 29}}
planners: [tdij]
""")
    text = exp.read_text().replace("reference: tdij\n", "")
    exp.write_text(text)
    run_bench(exp, tmp_path / "s.db", workers=1, progress=False)
    rows = comparable_rows(tmp_path / "s.db")
    assert len(rows) == 10
    scen = (MOVINGAI / "den312d.map.scen").read_text().splitlines()
    for r in rows.values():
        opt = float(scen[r["scen_line"] - 1].split("\t")[8])
        assert r["reference_source"] == "scen" and r["reference_length"] == opt
        # the independent Dijkstra matches the benchmark's optimum (8 decimals)
        assert r["solution_length"] == pytest.approx(opt, abs=1e-6)
        assert abs(r["R_length"]) < 1e-8


def test_make_batches_keeps_maps_together():
    from pathfuse.bench.experiment import RunSpec

    def spec(i, m):
        return RunSpec(key=str(i), problem_key="p", index=i, kind="static", group="g",
                       map_index=0, planner_index=0, config="c", planner="x", params={},
                       full_params={}, seed=0, query={}, query_index=0, map_key=m,
                       map_spec={}, limits={}, robot_radius_m=0.0, reference=None,
                       payload="{}")

    runs = [spec(i, "a" if i < 5 else "b" if i < 7 else "c") for i in range(10)]
    batches = make_batches(runs, workers=2, batch_size=4)
    flat = [r.index for b in batches for g in b for r in g]
    assert flat == list(range(10))  # nothing lost, order kept
    assert all(sum(len(g) for g in b) <= 4 for b in batches)
    assert all(len({r.map_key for r in g}) == 1 for b in batches for g in b)
    assert make_batches([], workers=2) == []


def test_real_planners_on_paper_maps(tmp_path):
    p = tmp_path / "real.yaml"
    p.write_text("""
seeds: 3
maps: [paper]
planners:
  - astar
  - apf
  - name: fusion
    params: {r1_m: [1, 2]}
""")
    s = run_bench(p, tmp_path / "real.db", workers=2, progress=False)
    assert s.complete and s.errors == 0
    rows = comparable_rows(tmp_path / "real.db")
    import pathfuse

    for r in rows.values():
        if r["planner"] == "astar":
            direct = pathfuse.plan(paper_map(r["seed"]), PAPER_START, PAPER_GOAL)
            assert r["solution_length"] == pytest.approx(direct.length)
            assert r["R_length"] == 0.0 and r["reference_source"] == "astar"
        if r["solved"] and r["reference_length"]:
            assert r["R_length"] == pytest.approx(
                (r["solution_length"] - r["reference_length"]) / r["reference_length"])


def test_dynamic_runs_match_direct_simulation(tmp_path):
    world = pytest.importorskip("pathfuse.world")
    (tmp_path / "sc.yaml").write_text("""
map: {rows: ["............", "............", "............", "............"]}
start: [0.5, 1.5]
goal: [11.5, 1.5]
robot: {radius: 0.2}
obstacles:
  - {position: [6.0, 3.5], velocity: [0.0, -0.5], radius: 0.3}
""")
    exp = tmp_path / "dyn.yaml"
    exp.write_text("""
seeds: 2
maps:
  - name: corridor
    dynamic: sc.yaml
  - name: family
    dynamic: {generate: {moving: 2, speed_range: [0.3, 0.6]}}
planners: [astar-follow, {name: apf, params: {k_att: [20, 40]}}]
""")
    s = run_bench(exp, tmp_path / "d.db", workers=1, progress=False)
    assert s.complete and s.errors == 0 and s.total == 2 * 2 * 3
    run_bench(exp, tmp_path / "p.db", workers=2, progress=False)
    rows = comparable_rows(tmp_path / "d.db")
    assert rows == comparable_rows(tmp_path / "p.db")
    from pathfuse.world.generate import generate_scenarios

    for r in rows.values():
        if r["map_name"] == "corridor":
            sc = world.load_scenario(tmp_path / "sc.yaml")
        else:
            sc = generate_scenarios(1, moving=2, speed_range=[0.3, 0.6], seed=r["seed"])[0]
        params = json.loads(r["config_settings"])
        choice = {"name": r["planner"], "params": {"k_att": params["k_att"]}} \
            if r["planner"] == "apf" else r["planner"]
        ep = world.simulate(sc, planner=choice, seed=r["seed"])
        assert r["status_name"] == ep.status.name and bool(r["solved"]) == ep.reached
        assert r["steps"] == ep.n_ticks
        assert r["collisions"] == (0 if ep.collision_with is None else 1)
        assert r["solution_clearance"] == pytest.approx(ep.min_distance_m)
        assert (r["start_x"], r["start_y"]) == tuple(sc.start)
        if ep.reached:
            assert r["time_to_goal"] == pytest.approx(ep.time_to_goal_s)
            assert r["solution_length"] == pytest.approx(ep.path_length_m)
        else:
            assert r["time_to_goal"] is None and r["solution_length"] is None
    assert {r["status_name"] for r in rows.values()} & {"SUCCESS"}


def test_workers_that_cannot_start_stop_the_sweep_at_once(tmp_path):
    from pathfuse.bench.runner import WorkersCannotStart

    exp = paper_study(tmp_path, seeds=2)
    # the plug-in imports in this process but fails in every worker process
    (tmp_path / "tplug.py").write_text(PLUGIN + (
        "\nimport multiprocessing\n"
        "if multiprocessing.parent_process() is not None:\n"
        "    raise ImportError('this plug-in refuses to load in a worker')\n"))
    t0 = time.monotonic()
    with pytest.raises(WorkersCannotStart, match="workers=1"):
        run_bench(exp, tmp_path / "w.db", workers=2, progress=False)
    assert time.monotonic() - t0 < 60
    with ResultStore(tmp_path / "w.db", readonly=True) as st:
        assert st.count() == 0
        assert st.conn.execute("SELECT state FROM pathfuse_sessions").fetchone()[0] == "failed"
    # in-process the same sweep runs
    assert run_bench(exp, tmp_path / "w.db", workers=1, progress=False).errors == 0


def test_the_sweep_summary_counts_runs_in_words():
    """One run is "1 run", not "1 runs" (issue 19's leftover), in every line that counts."""
    from pathfuse.bench.runner import SweepSummary

    one = SweepSummary("tiny", "t.db", total=4, skipped=3, ran=1, succeeded=1, wall_s=0.5)
    text = str(one)
    assert "tiny: 1 run in 0.5 s" in text and "of the 1 run now: solved 1" in text
    assert "1 runs" not in text
    many = str(SweepSummary("tiny", "t.db", total=4, ran=4, succeeded=4, wall_s=1.0))
    assert "tiny: 4 runs in 1.0 s" in many and "of the 4 runs now" in many
    done = str(SweepSummary("tiny", "t.db", total=1, skipped=1))
    assert "nothing to run, its one run is already stored in t.db" in done
    assert "summarises it)" in done


def test_the_study_summaries_count_in_words():
    """A one-episode dynamic run says "1 episode (1 planner x 1 disc count x 1 scenario)"."""
    from pathfuse.cli.commands import dynamic_headline as headline
    from pathfuse.studies.dynamic import DynamicConfig, DynamicRun

    cfg = DynamicConfig(n_seeds=1, moving=(0,), planners=("fusion",))
    one = headline(DynamicRun(cfg, [{}], 2.0, workers=1))
    assert one.startswith("1 episode (1 planner x 1 disc count x 1 scenario) in 2.00 s")
    assert one.endswith(", 1 worker)")
    cfg = DynamicConfig(n_seeds=3, moving=(0, 2), planners=("fusion", "dwa"))
    many = headline(DynamicRun(cfg, [{}] * 12, 2.0, workers=2))
    assert many.startswith("12 episodes (2 planners x 2 disc counts x 3 scenarios)")
    assert many.endswith(", 2 workers)")
