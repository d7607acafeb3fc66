"""OMPL's own tools on a pathfuse study: Planner Arena loads it, OMPL's script appends to it.

The tools are the real ones: ``plannerarena.database.load_database`` (PyPI
``plannerarena``, what the app runs on an uploaded database) and
``ompl_benchmark_statistics`` (PyPI ``ompl``, the official bindings), which
appends ``tests/data/ompl/*.log``, logs written by OMPL's own ``Benchmark``
class (``tests/data/make_ompl_logs.py``).  Both are in the ``test`` extra.
"""

from __future__ import annotations

import math
import shutil
import sqlite3
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

from pathfuse.bench import ResultStore, comparable_rows, run_bench
from pathfuse.bench.report import build_report, load_study
from pathfuse.bench.schema import OMPL_STATUS_TEXT, STATUS_TO_OMPL

pl = pytest.importorskip("polars")
pytest.importorskip("ompl")
arena = pytest.importorskip("plannerarena.database")

DATA = Path(__file__).resolve().parent / "data"
REPO = DATA.parents[1]
LOGS = [DATA / "ompl" / "merge-room.log", DATA / "ompl" / "merge-walled.log"]

# the room of the OMPL logs (tests/data/make_ompl_logs.py), and a dynamic scenario
EXPERIMENT = f"""
name: merge
seeds: 2
maps:
  - name: room
    map:
      rows: ["..........", "..........", "..........", "....##....", "....##....",
             "....##....", "....##....", "....##....", "....##....", "....##...."]
    start: [1.0, 1.0]
    goal: [9.0, 1.0]
  - name: crossing
    dynamic: {REPO / "examples" / "scenarios" / "crossing.yaml"}
planners:
  - name: astar
    params: {{heuristic: [euclidean, octile]}}
  - apf
  - fusion
"""


def ompl_script(*args: object) -> subprocess.CompletedProcess[str]:
    """``ompl_benchmark_statistics ARGS`` (the console script of PyPI ``ompl``)."""
    exe = shutil.which("ompl_benchmark_statistics", path=str(Path(sys.executable).parent))
    cmd = [exe] if exe else [sys.executable, "-m", "ompl.ompl_benchmark_statistics"]
    return subprocess.run([*cmd, *map(str, args)], capture_output=True, text=True,
                          timeout=300)


@pytest.fixture(scope="module")
def study(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("merge")
    (d / "merge.yaml").write_text(EXPERIMENT)
    s = run_bench(d / "merge.yaml", d / "merge.db", workers=1, progress=False)
    assert s.complete and s.errors == 0
    return d / "merge.db"


@pytest.fixture(scope="module")
def merged(study, tmp_path_factory) -> tuple[Path, Path]:
    """The study with OMPL's logs appended, and a database of the logs alone."""
    d = tmp_path_factory.mktemp("ompl")
    db = d / "merged.db"
    shutil.copy(study, db)
    p = ompl_script("-a", "-d", db, *LOGS)
    assert p.returncode == 0, p.stderr
    only = d / "ompl-only.db"
    p = ompl_script("-d", only, *LOGS)
    assert p.returncode == 0, p.stderr
    return db, only


def table_info(db: Path, table: str) -> list[tuple]:
    conn = sqlite3.connect(db)
    try:
        return [tuple(r[1:]) for r in conn.execute(f"PRAGMA table_info({table})")]
    finally:
        conn.close()


def decoded(data: dict) -> pl.DataFrame:
    """Planner Arena's runs with the status text its bar chart shows (its own join)."""
    enum = data["enums"].filter(pl.col("name") == "status").select("value", "description")
    return data["runs"].join(enum, left_on="status", right_on="value")


# --------------------------------------------------------------------------- layout
def test_ompl_tables_are_created_as_the_ompl_script_creates_them(study, merged):
    _, only = merged
    for table in ("experiments", "plannerConfigs", "enums"):
        assert table_info(study, table) == table_info(only, table), table
    # then one column per property, added as runs report them
    assert table_info(study, "progress")[:2] == table_info(only, "progress")[:2]
    assert table_info(study, "runs")[:3] == table_info(only, "runs")[:3]


# --------------------------------------------------------------------------- Planner Arena
def test_planner_arena_loads_the_study_with_every_configuration_and_numeric_attributes(study):
    data = arena.load_database(study)
    runs = data["runs"]
    with ResultStore(study, readonly=True) as st:
        rows = st.results()
        configs = [r[0] for r in st.conn.execute("SELECT name FROM plannerConfigs")]
    assert len(configs) == len(set(configs)) == 4  # astar x 2, apf, fusion (static+dynamic)
    assert sorted(runs["planner"].unique().cast(pl.String).to_list()) == sorted(configs)
    assert data["problem_names"] == ["merge/room", "merge/crossing"]
    assert data["parameters"] == []  # pathfuse adds no problem parameter
    assert runs.height == len(rows)
    for attr in data["attributes"]:
        col = runs[attr]
        assert col.dtype.is_numeric(), (attr, col.dtype)
        assert col.null_count() < runs.height, f"{attr} would plot empty"
    assert {"time", "solved", "status", "memory", "solution length", "path length",
            "time to goal", "collisions"} <= set(data["attributes"])
    # the status bar chart: OMPL's text of each run's pathfuse status
    want = Counter((r["config"], OMPL_STATUS_TEXT[STATUS_TO_OMPL[r["status_name"]]])
                   for r in rows)
    got = Counter(decoded(data).select(pl.col("planner").cast(pl.String), "description")
                  .iter_rows())
    assert got == want
    assert {"Exact solution", "Abort"} <= {d for _, d in want}


def test_planner_arena_progress_tab_has_the_episodes(study):
    data = arena.load_database(study)
    prog = data["progress"]
    assert prog.columns[:2] == ["runid", "time"]
    assert {"distance to goal", "clearance"} <= set(prog.columns[2:])
    with ResultStore(study, readonly=True) as st:
        dyn = {r["id"]: r for r in st.results("kind = 'dynamic'")}
    assert set(prog["runid"].unique().to_list()) == set(dyn)  # every episode, nothing else
    for rid, r in dyn.items():
        p = prog.filter(pl.col("runid") == rid).sort("time")
        t = p["time"].to_list()
        assert t[0] == 0.0 and t == sorted(set(t))
        assert p["distance to goal"][0] == pytest.approx(math.hypot(
            r["goal_x"] - r["start_x"], r["goal_y"] - r["start_y"]))
        if r["solved"]:  # the last sample is the tick that reached the goal
            assert t[-1] == pytest.approx(r["time_to_goal"])
            assert p["distance to goal"][-1] <= 0.25 + 1e-9  # crossing.yaml's tolerance
        assert min(p["clearance"]) >= r["solution_clearance"] - 1e-9


def test_planner_arena_shows_a_sweeps_configurations_apart(tmp_path):
    exp = REPO / "experiments" / "fusion-sweep-r1-r2-step.yaml"
    s = run_bench(exp, tmp_path / "sweep.db", seeds=1, workers=1, progress=False)
    assert s.ran == 36
    data = arena.load_database(tmp_path / "sweep.db")
    planners = data["runs"]["planner"].unique().cast(pl.String).to_list()
    assert len(planners) == 36
    assert "fusion(r1_m=0.5,r2_m=1,step_m=0.05)" in planners


# --------------------------------------------------------------------------- OMPL's script
def test_the_ompl_script_appends_its_logs_and_both_decode(study, merged):
    db, only = merged
    both, alone = decoded(arena.load_database(db)), decoded(arena.load_database(only))
    cols = ["experiment", "planner", "status", "description", "solved", "time"]

    def rows(df: pl.DataFrame) -> list[tuple]:
        return sorted(df.filter(pl.col("version").cast(pl.String).str.starts_with("OMPL"))
                      .select(pl.col(c).cast(pl.String) for c in cols).iter_rows())

    assert rows(both) == rows(alone) and len(rows(both)) == 12
    texts = {(e, p): d for e, p, _, d, _, _ in rows(both)}
    assert texts[("merge/room", "RRTConnect")] == "Exact solution"
    assert texts[("merge/walled", "RRTstar")] == "Approximate solution"
    # pathfuse's runs read as before the merge, in Planner Arena and in pathfuse
    before = decoded(arena.load_database(study)).select(cols).sort("time")
    after = both.filter(pl.col("version").cast(pl.String).str.starts_with("pathfuse")) \
        .select(cols).sort("time")
    assert before.cast({"experiment": pl.String}).equals(after.cast({"experiment": pl.String}))
    assert comparable_rows(db) == comparable_rows(study)


def test_pathfuse_reads_the_merged_study(study, merged, tmp_path):
    db, _ = merged
    with ResultStore(db, readonly=True) as st:
        ompl = st.results("run_key IS NULL")
        best = st.conn.execute("SELECT COUNT(*) FROM bestPlannerConfigs").fetchone()[0]
    assert len(ompl) == 12 and best == 6  # OMPL's own view: one row per planner name
    assert {r["config"] for r in ompl} == {"geometric_RRTConnect", "geometric_RRTstar"}
    assert {r["status_text"] for r in ompl} == {"Exact solution", "Approximate solution"}
    s = load_study(db)
    assert s.kinds == ["static", "dynamic", "ompl"]
    rep = build_report(db)
    by = {(r["scope"], r["config"]): r for r in rep.rows}
    walled = by[("merge/walled [OMPL 2.0.1]", "geometric_RRTstar")]
    assert (walled["runs"], walled["solved"]) == (3, 0)  # an approximate solution is no success
    assert walled["failures"] == "Approximate solution:3"
    room = by[("merge/room [OMPL 2.0.1]", "geometric_RRTConnect")]
    assert (room["runs"], room["solved"]) == (3, 3)
    assert by[("room", "apf")]["runs"] == 2
    assert rep.write(tmp_path / "out")["summary_csv"].exists()
    # the sweep resumes on the merged study: OMPL's runs are not taken for pathfuse's
    (tmp_path / "merge.yaml").write_text(EXPERIMENT)
    copy = tmp_path / "again.db"
    shutil.copy(db, copy)
    assert run_bench(tmp_path / "merge.yaml", copy, workers=1, progress=False).ran == 0
