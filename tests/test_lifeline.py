"""No process outlives a sweep: after SIGKILL or SIGTERM of `pathfuse bench`, its fork server,
resource tracker and workers end within seconds; SIGTERM ends the sweep like Ctrl-C."""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pathfuse.bench.lifeline import client_alive

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(),
                                reason="lists process groups through /proc (Linux)")

PLUGIN = '''
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
    t0 = time.perf_counter()
    time.sleep(params.sleep_s)
    path = np.array([start, goal], dtype=float)
    return PlanResult(Status.SUCCESS, path=path, length=float(np.hypot(*(goal - start))),
                      time_s=time.perf_counter() - t0)


register_function("segment", plan, Params, "straight segment (test plug-in)")
'''

EXPERIMENT = """imports: [seg.py]
seeds: 400
maps:
  - name: room
    map: {rows: ["......", ".##...", "......"]}
    start: [0.5, 0.5]
    goal: [5.5, 2.5]
planners:
  - name: segment
    params: {sleep_s: 0.02}
"""


def messages(err: str) -> list[str]:
    """stderr without the line that names the experiment's plug-in imports."""
    return [ln for ln in err.splitlines() if not ln.startswith("pathfuse bench: importing ")]


def group_pids(pgid: int) -> set[int]:
    """Live (non-zombie) processes of process group ``pgid``."""
    out = set()
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/stat", "rb") as fh:
                fields = fh.read().rsplit(b")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == pgid and fields[0] not in (b"Z", b"X"):
            out.add(int(d))
    return out


def count(db: Path) -> int:
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=5) as c:
            return int(c.execute("SELECT COUNT(*) FROM runs").fetchone()[0])
    except sqlite3.Error:
        return 0


def start_bench(tmp_path: Path, workers: int = 2) -> tuple[subprocess.Popen, list[str]]:
    (tmp_path / "seg.py").write_text(PLUGIN)
    (tmp_path / "slow.yaml").write_text(EXPERIMENT)
    cmd = [sys.executable, "-m", "pathfuse.cli", "bench", "slow.yaml", "--db", "s.db",
           "--workers", str(workers), "--batch-size", "4", "--no-progress"]
    proc = subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    deadline = time.monotonic() + 120
    while count(tmp_path / "s.db") < 8:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "no runs stored after 120 s"
        time.sleep(0.05)
    return proc, cmd


def wait_gone(pids: set[int], timeout_s: float) -> set[int]:
    deadline = time.monotonic() + timeout_s
    left = {p for p in pids if client_alive(p)}
    while left and time.monotonic() < deadline:
        time.sleep(0.05)
        left = {p for p in left if client_alive(p)}
    return left


def reap(proc: subprocess.Popen, pids: set[int]) -> None:
    """Clean up after a failed test: only the processes this test started."""
    for p in pids:
        if client_alive(p):
            try:
                os.kill(p, signal.SIGKILL)
            except ProcessLookupError:
                pass
    if proc.poll() is None:
        proc.kill()
    proc.wait(timeout=30)


@pytest.mark.slow
def test_sigkill_of_the_client_ends_every_process_it_started(tmp_path):
    proc, _ = start_bench(tmp_path)
    pids = group_pids(proc.pid)
    try:
        # the client, the fork server, the resource tracker and two workers
        assert len(pids) >= 5, pids
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
        left = wait_gone(pids - {proc.pid}, timeout_s=10)
        assert not left, f"still alive 10 s after kill -9 of the client: {sorted(left)}"
        assert not group_pids(proc.pid)
    finally:
        reap(proc, pids)


@pytest.mark.slow
def test_sigterm_ends_like_ctrl_c_and_the_same_command_resumes(tmp_path):
    proc, cmd = start_bench(tmp_path)
    pids = group_pids(proc.pid)
    try:
        t0 = time.monotonic()
        os.kill(proc.pid, signal.SIGTERM)
        out, err = proc.communicate(timeout=30)
        took = time.monotonic() - t0
        left = wait_gone(pids, timeout_s=10)
    finally:
        reap(proc, pids)
    assert proc.returncode == 143, (out, err)
    assert messages(err) == [
        "pathfuse bench: terminated (SIGTERM); run the same command again to resume"], err
    assert "interrupted: run the same command again" in out
    assert took < 15 and not left, (took, left)
    stored = count(tmp_path / "s.db")
    with sqlite3.connect(tmp_path / "s.db") as c:
        state, ran = c.execute("SELECT state, ran FROM pathfuse_sessions").fetchone()
    assert state == "interrupted" and ran == stored and 8 <= stored < 400
    again = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    assert f"{stored} already stored; 400/400" in again.stdout


def test_sigterm_of_a_single_process_command_is_one_line(tmp_path):
    """Any command (here an in-process sweep) ends on SIGTERM with one line and status 143."""
    (tmp_path / "seg.py").write_text(PLUGIN)
    (tmp_path / "slow.yaml").write_text(EXPERIMENT)
    proc = subprocess.Popen([sys.executable, "-m", "pathfuse.cli", "bench", "slow.yaml",
                             "--db", "s.db", "--workers", "1", "--no-progress"],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        deadline = time.monotonic() + 120
        while count(tmp_path / "s.db") < 3 and time.monotonic() < deadline:
            time.sleep(0.05)
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 143 and "Traceback" not in err, (out, err)
    assert len(messages(err)) == 1 and "terminated (SIGTERM)" in err
    assert count(tmp_path / "s.db") >= 3


def test_a_worker_ends_when_its_client_has_ended():
    """The library call a worker makes: watch_client ends the process after its client."""
    client = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    code = ("import sys, time; from pathfuse.bench.lifeline import watch_client; "
            f"watch_client({client.pid}); time.sleep(60); sys.exit(0)")
    worker = subprocess.Popen([sys.executable, "-c", code])
    try:
        time.sleep(0.5)
        assert worker.poll() is None
        client.kill()
        client.wait()
        assert worker.wait(timeout=10) == 75
    finally:
        for p in (client, worker):
            if p.poll() is None:
                p.kill()
                p.wait()
