"""A study written by an older pathfuse (schema 1) is migrated, never misread.

``tests/data/study-v1.sql`` is the SQL dump of a study that pathfuse's schema-1
store wrote (see ``tests/data/make_v1_study.py``): a static room and a dynamic
scenario, two configurations that share the name ``astar``, stored paths.
"""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest

from pathfuse.bench import ResultStore, run_bench
from pathfuse.bench.report import build_report, load_study
from pathfuse.bench.schema import OMPL_STATUS_TEXT, STATUS_TO_OMPL
from pathfuse.result import ConfigError

DATA = Path(__file__).resolve().parent / "data"
REPO = DATA.parents[1]
CROSSING = REPO / "examples" / "scenarios" / "crossing.yaml"

EXPERIMENT = f"""
name: legacy
seeds: 2
store_paths: true
maps:
  - name: room
    map:
      rows: ["..........", "..........", "..........", "....##....", "....##....",
             "....##....", "....##....", "....##....", "....##....", "....##...."]
    start: [1.0, 1.0]
    goal: [9.0, 1.0]
  - name: crossing
    dynamic: {CROSSING}
    seeds: [0]
planners:
  - {{name: astar, params: {{heuristic: octile}}}}
  - {{name: astar, params: {{heuristic: euclidean}}}}
  - apf
  - fusion
"""


def v1_study(tmp_path: Path) -> Path:
    db = tmp_path / "legacy.db"
    conn = sqlite3.connect(db)
    conn.executescript((DATA / "study-v1.sql").read_text(encoding="utf-8"))
    conn.execute("PRAGMA journal_mode = WAL")  # as the schema-1 store left its files
    conn.close()
    return db


def dump(db: Path) -> list[str]:
    conn = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
    try:
        return list(conn.iterdump())
    finally:
        conn.close()


def old_layout(db: Path) -> tuple[dict[str, dict], dict[int, tuple]]:
    """Runs (by key) and configurations of the schema-1 file, read as schema 1 lays them."""
    conn = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
    conn.row_factory = sqlite3.Row
    assert conn.execute("SELECT value FROM pathfuse_meta WHERE key = 'schema_version'") \
        .fetchone()[0] == "1"
    runs = {r["run_key"]: dict(r) for r in conn.execute("SELECT * FROM runs")}
    cfgs = {r[0]: tuple(r[1:]) for r in conn.execute(
        "SELECT id, name, planner, settings FROM plannerConfigs")}
    conn.close()
    return runs, cfgs


def check_migrated(rows: dict[str, dict], old: dict[str, dict]) -> None:
    assert set(rows) == set(old) and len(old) == 12
    for key, o in old.items():
        n = rows[key]
        for col, v in o.items():
            if col == "status":  # schema 1: pathfuse's own code
                continue
            assert n[col] == v, (key, col)
        code = STATUS_TO_OMPL[o["status_name"]]
        assert (n["status"], n["status_text"]) == (code, OMPL_STATUS_TEXT[code])
    assert {r["status_name"] for r in old.values()} >= {"SUCCESS", "LOCAL_MINIMUM"}
    assert sum(r["path"] is not None for r in rows.values()) >= 10


def test_bench_migrates_the_file_in_place_keeping_every_value(tmp_path):
    db = v1_study(tmp_path)
    old, cfgs = old_layout(db)
    with ResultStore(db) as st:
        rows = {r["run_key"]: r for r in st.results()}
        c = st.conn
        meta = dict(c.execute("SELECT key, value FROM pathfuse_meta").fetchall())
        names = dict(c.execute("SELECT id, name FROM plannerConfigs").fetchall())
        labels = {r[0]: (r[1], r[2]) for r in c.execute("SELECT * FROM pathfuse_configs")}
        cols = [r[1] for r in c.execute("PRAGMA table_info(plannerConfigs)")]
        exp_cols = [(r[1], r[2]) for r in c.execute("PRAGMA table_info(experiments)")]
        kinds = dict(c.execute("SELECT entry, kind FROM pathfuse_experiments").fetchall())
        run_types = {r[2] for r in c.execute("PRAGMA table_info(runs)")}
        seeds = {r[0] for r in c.execute("SELECT typeof(seed) FROM experiments")}
        legacy = c.execute("SELECT COUNT(*) FROM enums WHERE description = 'SUCCESS'") \
            .fetchone()[0]
    assert meta["schema_version"] == "2" and meta["migrated_from_schema"] == "1"
    check_migrated(rows, old)
    # the two "astar" configurations are named apart; pathfuse still finds them by its name
    assert cols == ["id", "name", "settings"]
    assert sorted(names.values()) == ["apf", "astar", "astar[heuristic=euclidean]", "fusion"]
    assert {i: (c[1], c[0]) for i, c in cfgs.items()} == labels
    assert len(exp_cols) == 12 and ("seed", "VARCHAR(24)") in exp_cols and seeds == {"text"}
    assert kinds == {"room": "static", "crossing": "dynamic"}
    assert run_types <= {"INTEGER", "REAL", "BOOLEAN", "ENUM"} and legacy == 0
    # the same experiment again finds every run whose key this version computes alike:
    # nothing was misread (a run whose key changed, because a later version added a robot
    # or planner setting, is run again, as it must be)
    from pathfuse.bench.experiment import load_experiment

    exp = tmp_path / "legacy.yaml"
    exp.write_text(EXPERIMENT)
    planned = {r.key for r in load_experiment(exp).expand()}
    stored = set(rows)
    # at least the 6 static runs of the room by astar (two settings) and apf; the fusion's
    # static runs are run again: the fusion gained parameters since (the social critics)
    assert len(planned & stored) >= 6
    assert run_bench(exp, db, workers=1, progress=False).ran == len(planned - stored)


def test_readers_migrate_a_copy_and_never_write_the_file(tmp_path):
    db = v1_study(tmp_path)
    before = dump(db)
    old, _ = old_layout(db)
    with ResultStore(db, readonly=True) as st:
        rows = {r["run_key"]: r for r in st.results()}
    check_migrated(rows, old)
    study = load_study(db)
    assert study.kinds == ["static", "dynamic"] and len(study.runs) == 12
    assert sorted(c.name for c in study.configs.values()) == \
        ["apf", "astar", "astar[heuristic=euclidean]", "fusion"]
    rep = build_report(db)
    files = rep.write(tmp_path / "out")
    assert files["summary_csv"].read_text().count("\n") > 4
    assert dump(db) == before  # still schema 1, every row as it was


def test_a_migration_that_fails_leaves_the_file_as_it_was(tmp_path):
    db = v1_study(tmp_path)
    conn = sqlite3.connect(db)  # foreign keys are off in a plain connection
    conn.execute("INSERT INTO runs (run_key, experimentid, plannerid, status_name) "
                 "VALUES ('dangling', 99, 1, 'SUCCESS')")
    conn.commit()
    conn.close()
    before = dump(db)
    with pytest.raises(ConfigError, match=r"legacy.db: cannot migrate the schema-1 study: "
                                          r"1 row\(s\) refer to missing rows"):
        ResultStore(db)
    assert dump(db) == before
    with pytest.raises(ConfigError, match="cannot migrate"):
        load_study(db)
