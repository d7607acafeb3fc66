"""The SQLite result store: OMPL's tables as OMPL writes them, pathfuse's side tables,
atomic writes, no duplicates, retries."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import numpy as np
import pytest

import pathfuse.bench.store as store_mod
from pathfuse.bench.schema import (
    ATTRIBUTE_COLUMNS,
    COLUMN_TABLE,
    OMPL_STATUS_TEXT,
    STATUS_TO_OMPL,
    OmplStatus,
    distinct_config_name,
    ompl_status,
)
from pathfuse.bench.store import (
    RUN_COLUMNS,
    STATUS_NAMES,
    WALL_CLOCK_COLUMNS,
    ResultStore,
    comparable_rows,
    schema_markdown,
)
from pathfuse.result import ConfigError, PathfuseError, Status

OMPL_TYPES = {"REAL", "INTEGER", "BOOLEAN", "ENUM"}


def _row(key, e, p, **kw):
    base = {"run_key": key, "experimentid": e, "plannerid": p, "status_name": "SUCCESS",
            "solved": True, "time": 0.5, "solution_length": 3.0, "seed": 1}
    base.update(kw)
    return base


def _full_row(key, e, p):
    """A run with a value in every column a worker and the runner fill."""
    row = _row(key, e, p, memory=80.0, solution_clearance=0.4, solution_smoothness=0.2,
               solution_segments=7, expansions=40, iterations=12, steps=8, collision_free=True,
               collisions=0, time_to_goal=4.5, path_length=3.0, R_length=0.02, wall_time=0.7,
               problem_key="pk", kind="dynamic", map_name="m", planner="fusion",
               query_index=0, scen_line=3, start_x=0.5, start_y=0.5, goal_x=3.0, goal_y=0.5,
               reference_length=2.94, reference_source="astar", message="ok", error=None,
               traceback=None, params='{"seed": 1}', metrics='{"steps": 8}', info="{}",
               timing='{"plan_s": 0.1}', path=b"\x00" * 32, headings=b"\x00" * 16,
               pathfuse_version="0", host="h", worker="w", started_at="t0", finished_at="t1")
    assert set(row) == {c for c, _, _ in RUN_COLUMNS} - {"id", "status"}
    return row


@pytest.fixture
def st(tmp_path):
    with ResultStore(tmp_path / "s.db") as s:
        yield s


def _cols(conn, table):
    return [(r[1], r[2]) for r in conn.execute(f"PRAGMA table_info({table})")]


def test_ompl_tables_have_exactly_the_columns_ompl_creates(st):
    c = st.conn
    assert _cols(c, "experiments") == [
        ("id", "INTEGER"), ("name", "VARCHAR(512)"), ("totaltime", "REAL"),
        ("timelimit", "REAL"), ("memorylimit", "REAL"), ("runcount", "INTEGER"),
        ("version", "VARCHAR(128)"), ("hostname", "VARCHAR(1024)"), ("cpuinfo", "TEXT"),
        ("date", "DATETIME"), ("seed", "VARCHAR(24)"), ("setup", "TEXT")]
    assert _cols(c, "plannerConfigs") == [("id", "INTEGER"), ("name", "VARCHAR(512)"),
                                          ("settings", "TEXT")]
    assert _cols(c, "enums") == [("name", "VARCHAR(512)"), ("value", "INTEGER"),
                                 ("description", "TEXT")]
    assert _cols(c, "progress") == [("runid", "INTEGER"), ("time", "REAL")]
    assert _cols(c, "runs") == [
        ("id", "INTEGER"), ("experimentid", "INTEGER"), ("plannerid", "INTEGER"),
        ("time", "REAL"), ("solved", "BOOLEAN"), ("status", "ENUM"), ("memory", "REAL"),
        ("solution_length", "REAL"), ("solution_clearance", "REAL"),
        ("solution_smoothness", "REAL"), ("solution_segments", "INTEGER")]
    assert c.execute("PRAGMA journal_mode").fetchone()[0] == "wal"


def test_runs_holds_only_numeric_ompl_columns_after_a_full_run(st):
    e = st.ensure_experiment("s", "m", "dynamic")
    p = st.ensure_planner_config("fusion", "fusion", "{}")
    assert st.insert_runs([_full_row("k", e, p)]) == 1
    cols = _cols(st.conn, "runs")
    assert {t for _, t in cols[3:]} <= OMPL_TYPES
    names = {n.replace("_", " ") for n, _ in cols}  # Planner Arena's renaming
    assert not names & {"planner", "experiment", "version", "kind", "name", "run key"}
    assert {n for n, _ in cols[11:]} == {c for c, _, _ in ATTRIBUTE_COLUMNS}
    # pathfuse's text and blobs are in the side tables, under the run's id
    rid = st.conn.execute("SELECT id FROM runs").fetchone()[0]
    side = st.conn.execute("SELECT run_key, traceback, params, kind FROM pathfuse_runs "
                           "WHERE runid = ?", (rid,)).fetchone()
    assert tuple(side) == ("k", None, '{"seed": 1}', "dynamic")
    blobs = st.conn.execute("SELECT path, headings FROM pathfuse_paths WHERE runid = ?",
                            (rid,)).fetchone()
    assert tuple(blobs) == (b"\x00" * 32, b"\x00" * 16)
    # the view gives every column back, as it was written
    [got] = st.results()
    want = _full_row("k", e, p)
    assert {k: got[k] for k in want} == {k: (int(v) if isinstance(v, bool) else v)
                                         for k, v in want.items()}
    assert got["status"] == 6 and got["status_text"] == "Exact solution"


def test_attribute_columns_appear_when_a_run_first_has_a_value(st):
    e = st.ensure_experiment("s", "m", "static")
    p = st.ensure_planner_config("x", "x", "{}")
    st.insert_runs([_row("a", e, p, expansions=5)])
    have = {n for n, _ in _cols(st.conn, "runs")}
    assert "expansions" in have and "time_to_goal" not in have and "R_length" not in have
    assert st.results()[0]["time_to_goal"] is None  # still a key of every result row
    st.insert_runs([_row("b", e, p, time_to_goal=3.5)])
    assert ("time_to_goal", "REAL") in _cols(st.conn, "runs")
    assert [r["time_to_goal"] for r in st.results()] == [None, 3.5]


def test_status_is_the_ompl_enum_and_pathfuse_keeps_its_own(st):
    rows = st.conn.execute("SELECT value, description FROM enums WHERE name='status' "
                           "ORDER BY value").fetchall()
    assert [tuple(r) for r in rows] == list(enumerate(OMPL_STATUS_TEXT))
    assert (OMPL_STATUS_TEXT[4], OMPL_STATUS_TEXT[5], OMPL_STATUS_TEXT[6],
            OMPL_STATUS_TEXT[7]) == ("Timeout", "Approximate solution", "Exact solution",
                                     "Crash")
    vocab = {r[0]: r[1] for r in st.conn.execute("SELECT name, ompl_status FROM pathfuse_status")}
    assert vocab == {n: int(STATUS_TO_OMPL[n]) for n in STATUS_NAMES}
    assert set(STATUS_NAMES) == {s.name for s in Status} | {"ERROR"}
    e = st.ensure_experiment("s", "m", "static")
    p = st.ensure_planner_config("x", "x", "{}")
    names = list(STATUS_NAMES)
    st.insert_runs([_row(n, e, p, status_name=n, solved=n == "SUCCESS") for n in names])
    got = {r["status_name"]: (r["status"], r["status_text"]) for r in st.results()}
    assert got["SUCCESS"] == (6, "Exact solution")
    assert got["TIMEOUT"] == got["MAX_ITERATIONS"] == (4, "Timeout")
    assert got["ERROR"] == (7, "Crash")
    assert got["START_OCCUPIED"] == got["START_OUT_OF_BOUNDS"] == (1, "Invalid start")
    assert got["GOAL_OCCUPIED"] == got["GOAL_OUT_OF_BOUNDS"] == (2, "Invalid goal")
    assert got["NO_PATH"] == (9, "Infeasible problem")
    assert got["LOCAL_MINIMUM"] == got["COLLISION"] == (8, "Abort")
    assert not any(s == OmplStatus.APPROXIMATE_SOLUTION for s, _ in got.values())


def test_a_plugin_status_joins_the_vocabulary_and_keeps_the_ompl_meaning(st):
    e = st.ensure_experiment("s", "m", "static")
    p = st.ensure_planner_config("x", "x", "{}")
    st.insert_runs([_row("a", e, p, status_name="REACHED"),
                    _row("b", e, p, status_name="WANDERED", solved=False)])
    assert [(r["status_name"], r["status"]) for r in st.results()] == [("REACHED", 6),
                                                                         ("WANDERED", 0)]
    assert ompl_status("REACHED", True) == 6 and ompl_status(None, False) == 7
    row = st.conn.execute("SELECT ompl_status FROM pathfuse_status WHERE name = 'WANDERED'") \
        .fetchone()
    assert row[0] == OmplStatus.UNKNOWN


def test_insert_and_views(st):
    e = st.ensure_experiment("study", "paper", "static", runcount=2, timelimit=5.0, seed=7)
    p = st.ensure_planner_config("astar", "astar", '{"w":1}')
    assert st.ensure_experiment("study", "paper", "static", runcount=2) == e
    assert st.ensure_planner_config("astar", "astar", '{"w":1}') == p
    assert st.insert_runs([_row("a", e, p), _row("b", e, p, status_name="NO_PATH",
                                                 solved=False, solution_length=None)]) == 2
    res = st.results()
    assert [r["status_text"] for r in res] == ["Exact solution", "Infeasible problem"]
    assert res[0]["experiment"] == "study/paper" and res[0]["config"] == "astar"
    best = st.conn.execute("SELECT plannerid, avg_solved FROM bestPlannerConfigs").fetchall()
    assert [tuple(r) for r in best] == [(p, 0.5)]
    exp = st.conn.execute("SELECT name, seed, typeof(seed) FROM experiments").fetchone()
    assert tuple(exp) == ("study/paper", "7", "text")
    side = st.conn.execute("SELECT study, entry, kind FROM pathfuse_experiments").fetchone()
    assert tuple(side) == ("study", "paper", "static")


def test_configurations_sharing_a_name_are_named_apart(st):
    a = st.ensure_planner_config("astar", "astar", '{"heuristic": "octile", "w": 1}')
    b = st.ensure_planner_config("astar", "astar", '{"heuristic": "euclidean", "w": 1}')
    c = st.ensure_planner_config("astar", "astar", "not json")
    names = dict(st.conn.execute("SELECT id, name FROM plannerConfigs").fetchall())
    assert names == {a: "astar", b: "astar[heuristic=euclidean]", c: "astar#2"}
    # found again by the name pathfuse asked for
    assert st.ensure_planner_config("astar", "astar", '{"heuristic": "euclidean", "w": 1}') == b
    assert distinct_config_name("f", '{"a": 1.5, "b": 2}', ['{"a": 1, "b": 2}'], {"f"}) == \
        "f[a=1.5]"
    assert distinct_config_name("f", "{}", [], set()) == "f"


def test_an_ompl_experiment_of_the_same_name_is_another_experiment(st):
    st.conn.execute("INSERT INTO experiments (name, version) VALUES ('s/room', 'OMPL 2.0.1')")
    ompl_id = st.conn.execute("SELECT id FROM experiments").fetchone()[0]
    e = st.ensure_experiment("s", "room", "static")
    assert e != ompl_id
    assert st.ensure_experiment("s", "room", "static") == e


def test_no_duplicates_and_error_rows_are_replaced_only_on_retry(st):
    e = st.ensure_experiment("s", "m", "static")
    p = st.ensure_planner_config("x", "x", "{}")
    st.insert_runs([_row("k", e, p, solution_length=1.0)])
    assert st.insert_runs([_row("k", e, p, solution_length=2.0)]) == 0
    assert st.count() == 1
    assert st.results()[0]["solution_length"] == 1.0
    st.insert_runs([_row("bad", e, p, status_name="ERROR", solved=False, error="boom",
                         traceback="Traceback ...", progress=[{"time": 0.0, "x": 1.0}])])
    bad_id = st.results("run_key = 'bad'")[0]["id"]
    assert st.done_keys() == {"k", "bad"}
    assert st.done_keys(include_errors=False) == {"k"}
    assert st.insert_runs([_row("bad", e, p)]) == 1
    row = st.results("run_key = ?", ("bad",))[0]
    assert row["status_name"] == "SUCCESS" and row["error"] is None and row["status"] == 6
    assert row["traceback"] is None and row["id"] == bad_id  # replaced whole, same id
    assert st.conn.execute("SELECT COUNT(*) FROM progress").fetchone()[0] == 0
    assert st.count() == 2
    # the same key twice in one batch: the first result wins
    assert st.insert_runs([_row("d", e, p, time=1.0), _row("d", e, p, time=2.0)]) == 1
    assert st.results("run_key = 'd'")[0]["time"] == 1.0


def test_a_failing_batch_is_not_half_stored(st):
    e = st.ensure_experiment("s", "m", "static")
    p = st.ensure_planner_config("x", "x", "{}")
    with pytest.raises(PathfuseError, match=r"unknown result column\(s\): \['not_a_column'\]"):
        st.insert_runs([_row("ok", e, p), _row("broken", e, p, not_a_column=1)])
    assert st.count() == 0
    with pytest.raises(PathfuseError, match=r"s.db: a result row without its run_key "
                                            r"\(run_key = None\)"):
        st.insert_runs([_row("ok", e, p), _row(None, e, p)])
    assert st.count() == 0 and st.conn.execute("SELECT COUNT(*) FROM runs").fetchone()[0] == 0


def test_progress_samples_add_columns(st):
    e = st.ensure_experiment("s", "m", "dynamic")
    p = st.ensure_planner_config("x", "x", "{}")
    st.insert_runs([_row("k", e, p, progress=[{"time": 0.0, "distance_to_goal": 5.0},
                                                {"time": 0.5, "distance_to_goal": 4.0}])])
    rows = st.conn.execute("SELECT runid, time, distance_to_goal FROM progress "
                           "ORDER BY time").fetchall()
    runid = st.results()[0]["id"]
    assert [tuple(r) for r in rows] == [(runid, 0.0, 5.0), (runid, 0.5, 4.0)]
    assert ("distance_to_goal", "REAL") in _cols(st.conn, "progress")


def test_reopen_keeps_everything_and_sessions(tmp_path):
    path = tmp_path / "s.db"
    with ResultStore(path) as s:
        e = s.ensure_experiment("s", "m", "static")
        p = s.ensure_planner_config("x", "x", "{}")
        s.insert_runs([_row("k", e, p, wall_time=2.0)])
        s.update_totals()
        sid = s.start_session(study="s", planned=3)
        s.end_session(sid, state="finished", ran=1, errors=0)
    with ResultStore(path) as s:
        assert s.done_keys() == {"k"}
        assert s.ensure_experiment("s", "m", "static") == e
        row = s.conn.execute("SELECT state, planned, ran FROM pathfuse_sessions").fetchone()
        assert tuple(row) == ("finished", 3, 1)
        assert s.conn.execute("SELECT totaltime FROM experiments").fetchone()[0] == 2.0
    with ResultStore(path, readonly=True) as s:
        assert s.count() == 1
        with pytest.raises(sqlite3.OperationalError):
            s.conn.execute("DELETE FROM runs")


def test_update_totals_leaves_an_ompl_experiment_alone(st):
    st.conn.execute("INSERT INTO experiments (name, totaltime, version) "
                    "VALUES ('ompl/x', 12.5, 'OMPL 2.0.1')")
    e = st.ensure_experiment("s", "m", "static")
    p = st.ensure_planner_config("x", "x", "{}")
    st.insert_runs([_row("k", e, p, wall_time=1.5)])
    st.update_totals()
    got = dict(st.conn.execute("SELECT name, totaltime FROM experiments").fetchall())
    assert got == {"ompl/x": 12.5, "s/m": 1.5}


def test_bad_databases_are_config_errors(tmp_path):
    junk = tmp_path / "junk.db"
    junk.write_bytes(b"this is not sqlite at all" * 100)
    with pytest.raises(ConfigError, match="junk.db: not an SQLite database"):
        ResultStore(junk)
    with pytest.raises(ConfigError, match="no such study database"):
        ResultStore(tmp_path / "missing.db", readonly=True)
    with pytest.raises(ConfigError, match="does not exist"):
        ResultStore(tmp_path / "no" / "dir" / "x.db")
    newer = tmp_path / "newer.db"
    with ResultStore(newer) as s:
        s.conn.execute("UPDATE pathfuse_meta SET value='99' WHERE key='schema_version'")
    for ro in (False, True):
        with pytest.raises(ConfigError, match=r"newer.db: written by a newer pathfuse "
                                              r"\(schema 99 > 2\)"):
            ResultStore(newer, readonly=ro)
    odd = tmp_path / "odd.db"
    with ResultStore(odd) as s:
        s.conn.execute("UPDATE pathfuse_meta SET value='two' WHERE key='schema_version'")
    with pytest.raises(ConfigError, match="odd.db: unknown pathfuse schema version 'two'"):
        ResultStore(odd, readonly=True)


def test_comparable_rows_drop_clock_columns(tmp_path):
    paths = []
    for i, t in enumerate((0.1, 0.9)):
        path = tmp_path / f"{i}.db"
        with ResultStore(path) as s:
            e = s.ensure_experiment("s", "m", "static")
            p = s.ensure_planner_config("x", "x", '{"a": 1}')
            if i:  # ids differ between the two stores
                s.ensure_planner_config("y", "y", "{}")
            s.insert_runs([_row("k", e, p, time=t, host=f"h{i}", wall_time=t)])
        paths.append(path)
    a, b = (comparable_rows(p) for p in paths)
    assert a == b and "time" not in a["k"] and a["k"]["config_name"] == "x"
    assert a["k"]["config_settings"] == '{"a": 1}' and a["k"]["experiment_name"] == "s/m"
    assert comparable_rows(paths[0], exclude=()) != comparable_rows(paths[1], exclude=())


def test_schema_is_documented():
    doc = store_mod.__doc__
    for name, _, _ in RUN_COLUMNS:
        assert f"``{name}``" in doc, name
    assert set(COLUMN_TABLE) == {c for c, _, _ in RUN_COLUMNS}
    assert WALL_CLOCK_COLUMNS <= {c for c, _, _ in RUN_COLUMNS}
    md = schema_markdown()
    assert md.count("\n") == len(RUN_COLUMNS) + 1
    assert "| `R_length` | REAL | `runs` |" in md and "| `params` | TEXT | `pathfuse_runs` |" in md


def test_queries_of_ompl_style_readers_work(st):
    """The queries a reader written for OMPL's databases makes (columns by declared type)."""
    e = st.ensure_experiment("s", "paper", "static", timelimit=5.0, runcount=2)
    p1 = st.ensure_planner_config("astar", "astar", "{}")
    p2 = st.ensure_planner_config("apf", "apf", "{}")
    st.insert_runs([_row("a", e, p1), _row("b", e, p2, status_name="LOCAL_MINIMUM",
                                             solved=False, solution_length=None)])
    c = st.conn
    planners = c.execute("SELECT id, name FROM plannerConfigs").fetchall()
    cols = c.execute("PRAGMA table_info(runs)").fetchall()[3:]
    assert {col[2] for col in cols} <= OMPL_TYPES
    for col in cols:
        for pid, _ in planners:
            c.execute(f'SELECT "{col[1]}" FROM runs WHERE plannerid = ? AND "{col[1]}" '
                      "IS NOT NULL", (pid,)).fetchall()
    descriptions = [r[0] for r in c.execute(
        "SELECT description FROM enums WHERE name IS 'status' ORDER BY value")]
    used = [r[0] for r in c.execute("SELECT status FROM runs ORDER BY id")]
    assert [descriptions[v] for v in used] == ["Exact solution", "Abort"]
    exp = c.execute("SELECT id, name, timelimit, memorylimit FROM experiments").fetchall()
    assert [tuple(r) for r in exp] == [(e, "s/paper", 5.0, 0.0)]
    per = c.execute("SELECT count(*) FROM runs WHERE runs.experimentid = ? "
                    "GROUP BY runs.plannerid", (e,)).fetchall()
    assert [r[0] for r in per] == [1, 1]
    settings = [json.loads(r[0]) for r in c.execute("SELECT settings FROM plannerConfigs")]
    assert settings == [{}, {}]


def test_an_episode_reports_its_progress():
    from pathfuse import simulate
    from pathfuse.bench.execute import MAX_PROGRESS_SAMPLES, episode_progress, episode_row

    ep = simulate(Path(__file__).resolve().parents[1] / "examples" / "scenarios" /
                  "crossing.yaml", planner="apf", seed=0)
    n = ep.positions.shape[0]
    assert n > MAX_PROGRESS_SAMPLES  # long enough to be thinned
    samples = episode_progress(ep)
    assert len(samples) == MAX_PROGRESS_SAMPLES == 100
    t = [s["time"] for s in samples]
    assert t[0] == 0.0 and t[-1] == pytest.approx(ep.times[-1]) and t == sorted(set(t))
    goal = np.asarray(ep.scenario.goal)
    for s in samples:
        i = int(round(s["time"] / ep.scenario.dt))
        assert s["distance_to_goal"] == pytest.approx(float(np.hypot(*(ep.positions[i] - goal))))
        # never closer than the episode's own least clearance, never farther than the cap
        assert ep.min_distance_m - 1e-9 <= s["clearance"] <= 2.0 + 1e-9
    assert min(s["clearance"] for s in samples) < 2.0
    assert episode_row(ep)["progress"] == samples
