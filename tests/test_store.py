"""The SQLite result store: OMPL's layout, atomic writes, no duplicates, retries."""

from __future__ import annotations

import sqlite3

import pytest

import pathfuse.bench.store as store_mod
from pathfuse.bench.store import (
    RUN_COLUMNS,
    STATUS_NAMES,
    WALL_CLOCK_COLUMNS,
    ResultStore,
    comparable_rows,
    schema_markdown,
)
from pathfuse.result import ConfigError, PathfuseError, Status


def _row(key, e, p, **kw):
    base = {"run_key": key, "experimentid": e, "plannerid": p, "status_name": "SUCCESS",
            "solved": True, "time": 0.5, "solution_length": 3.0, "seed": 1}
    base.update(kw)
    return base


@pytest.fixture
def st(tmp_path):
    with ResultStore(tmp_path / "s.db") as s:
        yield s


def test_ompl_tables_and_columns(st):
    c = st.conn
    tables = {r[0] for r in c.execute("SELECT name FROM sqlite_master WHERE type='table'")}
    assert {"experiments", "plannerConfigs", "enums", "runs", "progress"} <= tables
    cols = [(r[1], r[2]) for r in c.execute("PRAGMA table_info(runs)")]
    # OMPL's plotting code skips the first three columns and reads the types
    assert [n for n, _ in cols[:3]] == ["id", "experimentid", "plannerid"]
    types = dict(cols)
    assert types["time"] == "REAL" and types["solved"] == "BOOLEAN"
    assert types["status"] == "ENUM" and types["memory"] == "REAL"
    for name in ("solution_length", "solution_clearance", "solution_smoothness"):
        assert types[name] == "REAL"
    exp_cols = [r[1] for r in c.execute("PRAGMA table_info(experiments)")]
    assert exp_cols[:12] == ["id", "name", "totaltime", "timelimit", "memorylimit", "runcount",
                             "version", "hostname", "cpuinfo", "date", "seed", "setup"]
    assert [r[1] for r in c.execute("PRAGMA table_info(plannerConfigs)")][:3] == \
        ["id", "name", "settings"]
    assert [r[1] for r in c.execute("PRAGMA table_info(progress)")] == ["runid", "time"]
    assert c.execute("PRAGMA journal_mode").fetchone()[0] == "wal"


def test_status_enum_matches_pathfuse_statuses(st):
    rows = st.conn.execute("SELECT value, description FROM enums WHERE name='status' "
                           "ORDER BY value").fetchall()
    assert [d for _, d in rows] == [s.name for s in Status] + ["ERROR"]
    assert [v for v, _ in rows] == list(range(len(STATUS_NAMES)))


def test_insert_resolves_status_and_views(st):
    e = st.ensure_experiment("study", "paper", "static", runcount=2, timelimit=5.0)
    p = st.ensure_planner_config("astar", "astar", '{"w":1}')
    assert st.ensure_experiment("study", "paper", "static", runcount=2) == e
    assert st.ensure_planner_config("astar", "astar", '{"w":1}') == p
    assert st.ensure_planner_config("astar", "astar", '{"w":2}') != p
    assert st.insert_runs([_row("a", e, p), _row("b", e, p, status_name="NO_PATH",
                                                 solved=False, solution_length=None)]) == 2
    res = st.results()
    assert [r["status_text"] for r in res] == ["SUCCESS", "NO_PATH"]
    assert res[0]["status"] == STATUS_NAMES.index("SUCCESS")
    assert res[0]["experiment"] == "study/paper" and res[0]["config"] == "astar"
    best = st.conn.execute("SELECT plannerid, avg_solved FROM bestPlannerConfigs").fetchall()
    assert [tuple(r) for r in best] == [(p, 0.5)]
    # a status name that is not known yet is appended to the enum, never renumbered
    st.insert_runs([_row("c", e, p, status_name="REACHED")])
    v = st.conn.execute("SELECT value FROM enums WHERE name='status' AND "
                        "description='REACHED'").fetchone()[0]
    assert v == len(STATUS_NAMES)


def test_no_duplicates_and_error_rows_are_replaced_only_on_retry(st):
    e = st.ensure_experiment("s", "m", "static")
    p = st.ensure_planner_config("x", "x", "{}")
    st.insert_runs([_row("k", e, p, solution_length=1.0)])
    assert st.insert_runs([_row("k", e, p, solution_length=2.0)]) == 0
    assert st.count() == 1
    assert st.results()[0]["solution_length"] == 1.0
    st.insert_runs([_row("bad", e, p, status_name="ERROR", solved=False, error="boom")])
    assert st.done_keys() == {"k", "bad"}
    assert st.done_keys(include_errors=False) == {"k"}
    assert st.insert_runs([_row("bad", e, p)]) == 1
    row = st.results("run_key = ?", ("bad",))[0]
    assert row["status_name"] == "SUCCESS" and row["error"] is None
    assert st.count() == 2


def test_a_failing_batch_is_not_half_stored(st):
    e = st.ensure_experiment("s", "m", "static")
    p = st.ensure_planner_config("x", "x", "{}")
    with pytest.raises(PathfuseError, match="unknown result column"):
        st.insert_runs([_row("ok", e, p), _row("broken", e, p, not_a_column=1)])
    assert st.count() == 0


def test_progress_samples_add_columns(st):
    e = st.ensure_experiment("s", "m", "dynamic")
    p = st.ensure_planner_config("x", "x", "{}")
    st.insert_runs([_row("k", e, p, progress=[{"time": 0.0, "distance_to_goal": 5.0},
                                                {"time": 0.5, "distance_to_goal": 4.0}])])
    rows = st.conn.execute("SELECT runid, time, distance_to_goal FROM progress "
                           "ORDER BY time").fetchall()
    runid = st.results()[0]["id"]
    assert [tuple(r) for r in rows] == [(runid, 0.0, 5.0), (runid, 0.5, 4.0)]


def test_reopen_keeps_everything_and_sessions(tmp_path):
    path = tmp_path / "s.db"
    with ResultStore(path) as s:
        e = s.ensure_experiment("s", "m", "static")
        p = s.ensure_planner_config("x", "x", "{}")
        s.insert_runs([_row("k", e, p)])
        sid = s.start_session(study="s", planned=3)
        s.end_session(sid, state="finished", ran=1, errors=0)
    with ResultStore(path) as s:
        assert s.done_keys() == {"k"}
        assert s.ensure_experiment("s", "m", "static") == e
        row = s.conn.execute("SELECT state, planned, ran FROM pathfuse_sessions").fetchone()
        assert tuple(row) == ("finished", 3, 1)
    with ResultStore(path, readonly=True) as s:
        assert s.count() == 1
        with pytest.raises(sqlite3.OperationalError):
            s.conn.execute("DELETE FROM runs")


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
    with pytest.raises(ConfigError, match="newer pathfuse"):
        ResultStore(newer)


def test_comparable_rows_drop_clock_columns(tmp_path):
    paths = []
    for i, t in enumerate((0.1, 0.9)):
        path = tmp_path / f"{i}.db"
        with ResultStore(path) as s:
            e = s.ensure_experiment("s", "m", "static")
            p = s.ensure_planner_config("x", "x", "{}")
            if i:  # ids differ between the two stores
                s.ensure_planner_config("y", "y", "{}")
            s.insert_runs([_row("k", e, p, time=t, host=f"h{i}", wall_time=t)])
        paths.append(path)
    a, b = (comparable_rows(p) for p in paths)
    assert a == b and "time" not in a["k"] and a["k"]["config_name"] == "x"
    assert comparable_rows(paths[0], exclude=()) != comparable_rows(paths[1], exclude=())


def test_schema_is_documented():
    doc = store_mod.__doc__
    for name, _, _ in RUN_COLUMNS:
        assert f"``{name}``" in doc, name
    assert WALL_CLOCK_COLUMNS <= {c for c, _, _ in RUN_COLUMNS}
    md = schema_markdown()
    assert md.count("\n") == len(RUN_COLUMNS) + 1 and "`R_length`" in md


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
    plotted = [(col[1], col[2]) for col in cols if col[2] in ("BOOLEAN", "ENUM", "INTEGER",
                                                              "REAL")]
    assert ("time", "REAL") in plotted and ("status", "ENUM") in plotted
    for name, _ in plotted:
        for pid, _ in planners:
            c.execute(f'SELECT "{name}" FROM runs WHERE plannerid = ? AND "{name}" IS NOT NULL',
                      (pid,)).fetchall()
    descriptions = [r[0] for r in c.execute(
        "SELECT description FROM enums WHERE name IS 'status' ORDER BY value")]
    used = [r[0] for r in c.execute("SELECT status FROM runs ORDER BY id")]
    assert [descriptions[v] for v in used] == ["SUCCESS", "LOCAL_MINIMUM"]
    exp = c.execute("SELECT id, name, timelimit, memorylimit FROM experiments").fetchall()
    assert [tuple(r) for r in exp] == [(e, "s/paper", 5.0, 0.0)]
    per = c.execute("SELECT count(*) FROM runs WHERE runs.experimentid = ? "
                    "GROUP BY runs.plannerid", (e,)).fetchall()
    assert [r[0] for r in per] == [1, 1]
    assert [r[1] for r in c.execute("PRAGMA table_info(progress)")][:2] == ["runid", "time"]
