"""Study databases that must be refused, untouched, in one line; one sweep per database."""

from __future__ import annotations

import hashlib
import random
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pathfuse.bench import ResultStore, run_bench
from pathfuse.bench.dbcheck import check_study_file
from pathfuse.bench.lock import StudyLocked, lock_path, study_lock
from pathfuse.result import ConfigError

STUDY = """
name: small
seeds: 40
maps:
  - name: paper
    map: paper
planners: [astar, apf]
"""


def cli(*args, cwd, timeout=300):
    return subprocess.run([sys.executable, "-m", "pathfuse.cli", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, timeout=timeout)


def one_line(proc, *fragments, code=2):
    assert proc.returncode == code, (proc.returncode, proc.stdout, proc.stderr)
    assert "Traceback" not in proc.stderr
    lines = [ln for ln in proc.stderr.splitlines()  # the plug-in imports are named first
             if not ln.startswith("pathfuse bench: importing ")]
    assert len(lines) == 1, proc.stderr
    for f in fragments:
        assert f in lines[0], lines[0]
    return lines[0]


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def files(folder: Path) -> set[str]:
    return {p.name for p in folder.iterdir()}


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A finished study of 80 runs (its WAL checkpointed into the file, as after a sweep)."""
    d = tmp_path_factory.mktemp("finished")
    (d / "exp.yaml").write_text(STUDY)
    s = run_bench(d / "exp.yaml", d / "study.db", workers=1, progress=False)
    assert s.ran == 80 and s.complete
    assert files(d) == {"exp.yaml", "study.db"}
    return d


def copy_study(finished: Path, tmp_path: Path) -> Path:
    (tmp_path / "exp.yaml").write_text(STUDY)
    (tmp_path / "study.db").write_bytes((finished / "study.db").read_bytes())
    return tmp_path / "study.db"


# --------------------------------------------------------------------------- damaged
@pytest.mark.parametrize("where", [0.3, 0.6, 0.85])
def test_random_bytes_in_a_finished_study_are_refused(finished, tmp_path, where):
    db = copy_study(finished, tmp_path)
    size = db.stat().st_size
    rng = random.Random(int(where * 100))
    with open(db, "r+b") as fh:  # 8 KB of random bytes, as in the issue
        fh.seek(int(where * (size - 8192)))
        fh.write(rng.randbytes(8192))
    before = digest(db)
    p = cli("bench", "exp.yaml", "--db", "study.db", "--workers", "1", cwd=tmp_path)
    one_line(p, "pathfuse bench: error: study.db: the database is damaged",
             "SQLite quick_check", "restore it from a copy")
    assert p.stdout == "" and digest(db) == before
    assert files(tmp_path) == {"exp.yaml", "study.db"}  # no -wal, -shm or lock file left
    r = cli("report", "study.db", "--out", "rep", cwd=tmp_path)
    one_line(r, "pathfuse report: error: study.db: the database is damaged")
    assert not (tmp_path / "rep").exists() and digest(db) == before
    with pytest.raises(ConfigError, match="the database is damaged"):
        ResultStore(db)


def test_an_intact_study_passes_the_check_and_resumes(finished, tmp_path):
    db = copy_study(finished, tmp_path)
    assert check_study_file(db, write=True) is False
    p = cli("bench", "exp.yaml", "--db", "study.db", "--workers", "1", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert "nothing to run, all 80 runs are already stored in study.db" in p.stdout


# --------------------------------------------------------------------------- not ours to write
def test_a_read_only_study_is_refused_untouched(finished, tmp_path):
    db = copy_study(finished, tmp_path)
    before, mtime = digest(db), db.stat().st_mtime_ns
    db.chmod(0o444)
    try:
        p = cli("bench", "exp.yaml", "--db", "study.db", "--seeds", "50", cwd=tmp_path)
        one_line(p, "study.db: is read-only (mode r--r--r--)",
                 "pathfuse report can read it")
        assert digest(db) == before and db.stat().st_mtime_ns == mtime
        assert files(tmp_path) == {"exp.yaml", "study.db"}
        r = cli("report", "study.db", "--out", "rep", cwd=tmp_path)  # reading is fine
        assert r.returncode == 0, r.stderr
        assert digest(db) == before
    finally:
        db.chmod(0o644)


def test_db_naming_a_folder_is_refused(tmp_path):
    (tmp_path / "exp.yaml").write_text(STUDY)
    (tmp_path / "runs").mkdir()
    p = cli("bench", "exp.yaml", "--db", "runs", cwd=tmp_path)
    one_line(p, "pathfuse bench: error: runs: is a folder, not a study database")
    assert list((tmp_path / "runs").iterdir()) == []
    assert files(tmp_path) == {"exp.yaml", "runs"}


@pytest.mark.parametrize("journal", ["delete", "wal"])
def test_another_applications_sqlite_file_is_refused_untouched(tmp_path, journal):
    (tmp_path / "exp.yaml").write_text(STUDY)
    other = tmp_path / "app.sqlite"
    con = sqlite3.connect(other)
    con.execute(f"PRAGMA journal_mode = {journal}")
    con.execute("CREATE TABLE customers (id INTEGER PRIMARY KEY, name TEXT)")
    con.execute("INSERT INTO customers (name) VALUES ('Ada')")
    con.commit()
    con.close()
    before = digest(other)
    p = cli("bench", "exp.yaml", "--db", "app.sqlite", cwd=tmp_path)
    one_line(p, "app.sqlite: not a pathfuse study database but another application's",
             "tables: customers", "untouched")
    assert digest(other) == before and files(tmp_path) == {"exp.yaml", "app.sqlite"}
    with sqlite3.connect(other) as con:  # still in its own journal mode, with its data
        assert con.execute("PRAGMA journal_mode").fetchone()[0] == journal
        assert con.execute("SELECT name FROM customers").fetchall() == [("Ada",)]


def test_an_empty_file_becomes_a_new_study(tmp_path):
    (tmp_path / "exp.yaml").write_text(STUDY.replace("seeds: 40", "seeds: 2"))
    (tmp_path / "new.db").write_bytes(b"")
    p = cli("bench", "exp.yaml", "--db", "new.db", "--workers", "1", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert "4 runs" in p.stdout


# --------------------------------------------------------------------------- one sweep
SLOW_PLUGIN = '''
from dataclasses import dataclass
import time
import numpy as np
from pathfuse.planners.registry import register_function
from pathfuse.result import PlanResult, Status


@dataclass(frozen=True)
class Params:
    seed: int = 0
    sleep_s: float = 0.0


def plan(grid, start, goal, params, budget):
    time.sleep(params.sleep_s)
    path = np.array([start, goal], dtype=float)
    return PlanResult(Status.SUCCESS, path=path, length=float(np.hypot(*(goal - start))),
                      time_s=params.sleep_s)


register_function("segment", plan, Params, "straight segment (test plug-in)")
'''

SLOW = """imports: [seg.py]
seeds: 100
maps:
  - name: room
    map: {rows: ["......", "......"]}
    start: [0.5, 0.5]
    goal: [5.5, 1.5]
planners:
  - name: segment
    params: {sleep_s: 0.03}
"""


def test_a_second_sweep_on_the_same_database_is_refused(tmp_path):
    (tmp_path / "seg.py").write_text(SLOW_PLUGIN)
    (tmp_path / "slow.yaml").write_text(SLOW)
    cmd = [sys.executable, "-m", "pathfuse.cli", "bench", "slow.yaml", "--db", "s.db",
           "--workers", "1", "--no-progress"]
    first = subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not lock_path(tmp_path / "s.db").exists() or not (tmp_path / "s.db").exists():
            assert first.poll() is None and time.monotonic() < deadline, first.communicate()
            time.sleep(0.02)
        t0 = time.monotonic()
        second = cli(*cmd[3:], cwd=tmp_path)
        assert time.monotonic() - t0 < 30
        line = one_line(second, "pathfuse bench: error: s.db: another pathfuse sweep is "
                        "writing this study (pid", str(first.pid), "pathfuse bench slow.yaml",
                        "wait for it to finish")
        assert "on " in line
        out, err = first.communicate(timeout=120)
    finally:
        if first.poll() is None:
            first.kill()
            first.wait()
    assert first.returncode == 0, err
    assert "100 runs" in out and "0 already stored" in out
    with sqlite3.connect(tmp_path / "s.db") as c:  # the second one ran nothing
        assert c.execute("SELECT COUNT(*) FROM runs").fetchone()[0] == 100
        assert c.execute("SELECT COUNT(*) FROM pathfuse_sessions").fetchone()[0] == 1
    assert not lock_path(tmp_path / "s.db").exists()  # released and removed at the end
    again = cli(*cmd[3:], cwd=tmp_path)  # after it: the same command is free to run
    assert again.returncode == 0 and "all 100 runs are already stored" in again.stdout


def test_the_lock_dies_with_a_killed_sweep(tmp_path):
    """A lock held by a process killed with kill -9 is free at once (no stale lock)."""
    db = tmp_path / "s.db"
    code = ("import time; from pathfuse.bench.lock import study_lock\n"
            f"with study_lock({str(db)!r}, what='holder'):\n"
            "    print('locked', flush=True); time.sleep(60)\n")
    holder = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        with pytest.raises(StudyLocked, match=f"pid {holder.pid} on .*holder"):
            with study_lock(db):
                pass
        holder.kill()
        holder.wait()
        assert lock_path(db).exists()  # left behind by kill -9, but not locked
        with study_lock(db):
            assert "pid" in lock_path(db).read_text()
        assert not lock_path(db).exists()
    finally:
        if holder.poll() is None:
            holder.kill()
            holder.wait()


def test_library_sweeps_take_the_lock_too(tmp_path):
    (tmp_path / "exp.yaml").write_text(STUDY.replace("seeds: 40", "seeds: 1"))
    with study_lock(tmp_path / "s.db", what="a test"):
        with pytest.raises(StudyLocked, match="another pathfuse sweep .*a test"):
            run_bench(tmp_path / "exp.yaml", tmp_path / "s.db", workers=1, progress=False)
    assert not (tmp_path / "s.db").exists()
