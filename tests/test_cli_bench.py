"""`pathfuse bench` and `pathfuse report`, end to end through a subprocess, as a user runs them."""

from __future__ import annotations

import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

TINY = """
name: tiny
seeds: 3
maps:
  - name: paper
    map: paper
planners:
  - astar
  - name: fusion
    params: {r1_m: [1.0, 2.0]}
"""

PLUGIN = '''
from dataclasses import dataclass
import time
import numpy as np
from pathfuse.planners.registry import register_function
from pathfuse.result import PlanResult, Status


@dataclass(frozen=True)
class Params:
    seed: int = 0
    raise_seed: int = -1
    sleep_s: float = 0.0


def plan(grid, start, goal, params, budget):
    if params.seed == params.raise_seed:
        raise ValueError(f"plug-in failure on seed {params.seed}")
    t0 = time.perf_counter()
    time.sleep(params.sleep_s)
    path = np.array([start, goal], dtype=float)
    return PlanResult(Status.SUCCESS, path=path, length=float(np.hypot(*(goal - start))),
                      time_s=time.perf_counter() - t0)


register_function("segment", plan, Params, "straight segment (test plug-in)")
'''

ROOM = """
maps:
  - name: room
    map: {rows: ["......", ".##...", "......"]}
    start: [0.5, 0.5]
    goal: [5.5, 2.5]
"""


def run(*args, cwd=None, timeout=300):
    return subprocess.run([sys.executable, "-m", "pathfuse.cli", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, timeout=timeout)


def assert_one_line_error(proc, *fragments, code=2):
    assert proc.returncode == code, (proc.returncode, proc.stdout, proc.stderr)
    assert "Traceback" not in proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, proc.stderr
    for f in fragments:
        assert f in lines[0], lines[0]


def count(db: Path, where: str = "1") -> int:
    con = sqlite3.connect(db)
    try:
        return con.execute(f"SELECT COUNT(*) FROM pathfuse_results WHERE {where}").fetchone()[0]
    finally:
        con.close()


def test_help_shows_examples():
    for cmd in ("bench", "report"):
        p = run(cmd, "--help")
        assert p.returncode == 0, p.stderr
        assert "examples:" in p.stdout and f"pathfuse {cmd} " in p.stdout
    top = run("--help")
    assert "pathfuse bench" in top.stdout and "pathfuse report" in top.stdout


def test_bench_resume_and_report(tmp_path):
    (tmp_path / "tiny.yaml").write_text(TINY)
    db = tmp_path / "tiny.db"
    p = run("bench", "tiny.yaml", "--db", db, "--workers", "1", "--no-progress", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert "tiny: 9 runs in" in p.stdout and "0 already stored; 9/9" in p.stdout
    assert "errors 0" in p.stdout and p.stderr == ""
    assert count(db) == 9 and count(db, "solved = 1") == 9
    con = sqlite3.connect(db)
    keys = con.execute("SELECT id, run_key, solution_length FROM pathfuse_results "
                       "ORDER BY id").fetchall()
    con.close()
    # the same command again: nothing new runs, nothing changes
    again = run("bench", "tiny.yaml", "--db", db, "--workers", "1", "--no-progress",
                cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    # said as such, not as "0 runs ... solved 0, not solved 0", which reads as an empty study
    assert again.stdout.splitlines() == [
        f"tiny: nothing to run, all 9 runs are already stored in {db} ('pathfuse report "
        f"{db}' summarises them)"]
    con = sqlite3.connect(db)
    assert con.execute("SELECT id, run_key, solution_length FROM pathfuse_results ORDER BY id") \
        .fetchall() == keys
    assert con.execute("SELECT COUNT(*) FROM pathfuse_sessions").fetchone()[0] == 2
    con.close()
    # more seeds: only the new ones run
    more = run("bench", "tiny.yaml", "--db", db, "--workers", "1", "--seeds", "0:4",
               "--no-progress", cwd=tmp_path)
    assert more.returncode == 0, more.stderr
    assert "tiny: 3 runs in" in more.stdout and "9 already stored; 12/12" in more.stdout
    rep = run("report", db, "--out", tmp_path / "rep")
    assert rep.returncode == 0, rep.stderr
    for f in ("report.html", "report.md", "summary.csv", "parameters.csv",
              "param_fusion_r1_m.png", "length_paper.png"):
        assert (tmp_path / "rep" / f).is_file(), f
    assert "12 runs" in rep.stdout
    line = [ln for ln in rep.stdout.splitlines() if ln.startswith("all ") and "astar" in ln][0]
    assert line.split()[2:4] == ["4", "100.0%"]  # 4 seeds, all solved
    # --reference and --param go through
    rep2 = run("report", db, "--out", tmp_path / "rep2", "--reference", "fusion(r1_m=2)",
               "--param", "k_att", "--link-images")
    assert rep2.returncode == 0, rep2.stderr
    assert (tmp_path / "rep2" / "param_fusion_k_att.png").is_file()
    assert "base64" not in (tmp_path / "rep2" / "report.html").read_text()


def test_runs_that_raise_exit_1_and_are_stored(tmp_path):
    (tmp_path / "seg.py").write_text(PLUGIN)
    (tmp_path / "e.yaml").write_text("imports: [seg.py]\nseeds: 4\n" + ROOM + """
planners:
  - name: segment
    params: {raise_seed: 2}
""")
    db = tmp_path / "e.db"
    p = run("bench", "e.yaml", "--db", db, "--workers", "1", "--no-progress", cwd=tmp_path)
    assert p.returncode == 1, (p.stdout, p.stderr)
    assert "errors 1" in p.stdout and "plug-in failure on seed 2" in p.stdout
    assert count(db) == 4 and count(db, "status_name = 'ERROR' AND seed = 2") == 1
    # plain re-run: the stored error is not retried; --retry-errors runs it again
    p = run("bench", "e.yaml", "--db", db, "--workers", "1", "--no-progress", cwd=tmp_path)
    assert p.returncode == 0 and "all 4 runs are already stored" in p.stdout
    assert "1 of them raised (ERROR), --retry-errors runs them again" in p.stdout
    p = run("bench", "e.yaml", "--db", db, "--workers", "1", "--no-progress",
            "--retry-errors", cwd=tmp_path)
    assert p.returncode == 1 and ": 1 run in" in p.stdout and "3 already stored" in p.stdout
    assert count(db) == 4
    rep = run("report", db, "--out", tmp_path / "rep")
    assert rep.returncode == 0, rep.stderr
    md = (tmp_path / "rep" / "report.md").read_text()
    assert "| segment | 4 | 3/4 = 75.0% [30.1, 95.4] | 1 | ERROR:1 |" in md


def test_ctrl_c_exits_130_and_the_same_command_resumes(tmp_path):
    (tmp_path / "seg.py").write_text(PLUGIN)
    (tmp_path / "slow.yaml").write_text("imports: [seg.py]\nseeds: 60\n" + ROOM + """
planners:
  - name: segment
    params: {sleep_s: 0.05}
""")
    db = tmp_path / "slow.db"
    cmd = [sys.executable, "-m", "pathfuse.cli", "bench", "slow.yaml", "--db", str(db),
           "--workers", "1", "--no-progress"]
    proc = subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            if db.exists():
                try:
                    if count(db) >= 3:
                        break
                except sqlite3.Error:
                    pass
            time.sleep(0.05)
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, (out, err)
    assert "Traceback" not in err
    assert "interrupted" in out and "run the same command again" in out
    stored = count(db)
    assert 3 <= stored < 60
    p = run(*cmd[3:], cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert f"{stored} already stored; 60/60" in p.stdout
    assert count(db) == 60 and count(db, "solved = 1") == 60


@pytest.mark.parametrize("args, fragments", [
    (["bench", "nope.yaml", "--db", "x.db"], ["pathfuse bench: error:", "nope.yaml"]),
    (["bench", "bad.yaml", "--db", "x.db"], ["bad.yaml", "planners[0]", "r1_m"]),
    (["bench", "bad.yaml", "--db", "x.db", "--seeds", "5:2"], ["--seeds", "'5:2'"]),
    (["bench", "bad.yaml", "--db", "no/such/dir/x.db", "--seeds", "1"], ["bad.yaml"]),
    (["bench", "bad.yaml", "--db", "x.db", "--workers", "0"], ["--workers"]),
    (["bench", "bad.yaml"], ["--db"]),
])
def test_bench_bad_input_is_one_line(tmp_path, args, fragments):
    (tmp_path / "bad.yaml").write_text(
        "maps: [{map: paper}]\nplanners: [{name: fusion, params: {r1_m: -1}}]\n")
    assert_one_line_error(run(*args, cwd=tmp_path), *fragments)
    assert not (tmp_path / "x.db").exists()


def test_bench_db_folder_missing_is_one_line(tmp_path):
    (tmp_path / "tiny.yaml").write_text(TINY)
    p = run("bench", "tiny.yaml", "--db", "no/such/dir/x.db", "--workers", "1", cwd=tmp_path)
    assert_one_line_error(p, "x.db", "does not exist")


def test_report_bad_databases_are_one_line(tmp_path):
    (tmp_path / "text.db").write_text("hello\n")
    con = sqlite3.connect(tmp_path / "other.db")
    con.execute("CREATE TABLE t (x)")
    con.commit()
    con.close()
    from pathfuse.bench.store import ResultStore

    ResultStore(tmp_path / "empty.db").close()
    cases = [("missing.db", "no such study database"),
             ("text.db", "not an SQLite database"),
             ("other.db", "not a pathfuse study database"),
             ("empty.db", "holds no runs yet"),
             (".", "is a folder")]
    for name, what in cases:
        p = run("report", name, "--out", "o", cwd=tmp_path)
        assert_one_line_error(p, "pathfuse report: error:", name, what)
    assert not (tmp_path / "o").exists()
