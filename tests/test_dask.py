"""The same sweep on a Dask cluster (a LocalCluster on the loopback) equals the local run."""

from __future__ import annotations

import sys

import pytest

from pathfuse.bench import ResultStore, comparable_rows, run_bench
from pathfuse.result import ConfigError

STUDY = """
name: dask-study
imports: [tplug.py]
reference: tdij
seeds: 4
maps:
  - name: paper
    map: paper
  - name: file
    map: {movingai: small.map}
    queries: [{start: [0.5, 0.5], goal: [5.5, 3.5]}, {start: [0.5, 3.5], goal: [5.5, 0.5]}]
  - name: moving
    dynamic: sc.yaml
    seeds: 2
planners:
  - tdij
  - name: astar-follow
    kinds: [dynamic]
  - name: tdij
    label: picky
    params: {sleep_s: [0.0, 0.001], raise_seed: 3}
"""

SMALL_MAP = "type octile\nheight 4\nwidth 6\nmap\n......\n.@@@..\n...@..\n......\n"


def _study(tmp_path):
    from test_runner import PLUGIN  # the same plain-Python test planner

    (tmp_path / "tplug.py").write_text(PLUGIN)
    (tmp_path / "small.map").write_text(SMALL_MAP)
    (tmp_path / "sc.yaml").write_text(
        'map: {rows: ["..........", "..........", ".........."]}\nstart: [0.5, 1.5]\n'
        'goal: [9.5, 1.5]\nrobot: {radius: 0.2}\n'
        'obstacles: [{position: [5.0, 2.5], velocity: [0.0, -0.4], radius: 0.3}]\n')
    p = tmp_path / "exp.yaml"
    p.write_text(STUDY)
    return p


def test_dask_cluster_results_equal_local_results(tmp_path):
    distributed = pytest.importorskip("distributed")
    exp = _study(tmp_path)
    local = run_bench(exp, tmp_path / "local.db", workers=1, progress=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None,
                                  silence_logs=40) as cluster:
        remote = run_bench(exp, tmp_path / "dask.db", scheduler=cluster.scheduler_address,
                           progress=False, batch_size=3)
        again = run_bench(exp, tmp_path / "dask.db", scheduler=cluster.scheduler_address,
                          progress=False)
    assert remote.total == local.total == 4 * 3 * 3 + 2
    assert remote.ran == remote.total and again.ran == 0
    assert remote.errors == local.errors == 2 * 3  # seed 3 raises in the two picky configs
    assert remote.workers == 2 and remote.scheduler == cluster.scheduler_address
    a, b = comparable_rows(tmp_path / "local.db"), comparable_rows(tmp_path / "dask.db")
    assert len(a) == remote.total and a == b
    with ResultStore(tmp_path / "dask.db", readonly=True) as st:
        workers = {r["worker"] for r in st.results()}
        scheds = st.conn.execute("SELECT scheduler FROM pathfuse_sessions").fetchall()
    # the runs were computed on the cluster's workers, not in this process
    assert all(w.startswith("tcp://127.0.0.1:") for w in workers) and len(workers) == 2
    assert [s[0] for s in scheds] == [cluster.scheduler_address] * 2


def test_missing_dask_is_a_clear_error(tmp_path, monkeypatch):
    exp = _study(tmp_path)
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    with pytest.raises(ConfigError, match=r"pip install 'pathfuse\[dask\]'"):
        run_bench(exp, tmp_path / "x.db", scheduler="tcp://127.0.0.1:8786", progress=False)
    assert not (tmp_path / "x.db").exists()


def test_unreachable_scheduler_is_a_config_error(tmp_path):
    pytest.importorskip("distributed")
    import socket

    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    exp = _study(tmp_path)
    with pytest.raises(ConfigError, match=f"scheduler: cannot connect to tcp://127.0.0.1:{port}"):
        run_bench(exp, tmp_path / "y.db", scheduler=f"tcp://127.0.0.1:{port}", progress=False)


# ---------------------------------------------------------------- a cluster that goes away
SEGMENT = '''
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
seeds: 200
maps:
  - name: room
    map: {rows: ["......", "......"]}
    start: [0.5, 0.5]
    goal: [5.5, 1.5]
planners:
  - name: segment
    params: {sleep_s: 0.03}
"""


def _messages(err: str) -> list[str]:
    """stderr without the line that names the experiment's plug-in imports."""
    return [ln for ln in err.splitlines() if not ln.startswith("pathfuse bench: importing ")]


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _stored(db, where="1"):
    import sqlite3

    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=5) as c:
            return int(c.execute(f"SELECT COUNT(*) FROM pathfuse_results WHERE {where}")
                       .fetchone()[0])
    except sqlite3.Error:
        return 0


class _Cluster:
    """A real scheduler and one worker, each a process group of its own, killable."""

    def __init__(self, tmp_path):
        import socket
        import subprocess
        import time

        self.port = _free_port()
        self.address = f"tcp://127.0.0.1:{self.port}"
        log = open(tmp_path / "cluster.log", "w")  # noqa: SIM115 - closed in stop()
        self.log = log
        self.scheduler = subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
             "--port", str(self.port), "--no-dashboard"],
            stdout=log, stderr=log, start_new_session=True)
        deadline = time.monotonic() + 60
        while True:
            try:
                socket.create_connection(("127.0.0.1", self.port), timeout=1).close()
                break
            except OSError:
                assert time.monotonic() < deadline, "the scheduler did not start"
                time.sleep(0.1)
        self.worker = subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_worker", self.address,
             "--nworkers", "1", "--nthreads", "1", "--no-dashboard"],
            stdout=log, stderr=log, start_new_session=True)
        import distributed

        with distributed.Client(self.address, timeout="30s", set_as_default=False) as c:
            c.wait_for_workers(1, timeout=60)

    def kill(self, proc) -> None:
        import os
        import signal

        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait(timeout=30)

    def stop(self) -> None:
        self.kill(self.worker)
        self.kill(self.scheduler)
        self.log.close()


def _bench(tmp_path, *extra):
    import subprocess

    (tmp_path / "seg.py").write_text(SEGMENT)
    (tmp_path / "slow.yaml").write_text(SLOW)
    cmd = [sys.executable, "-m", "pathfuse.cli", "bench", "slow.yaml", "--db", "s.db",
           "--batch-size", "2", "--no-progress", *extra]  # stderr: the messages alone
    return subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True), cmd


def _wait_stored(proc, db, n, timeout=120):
    import time

    deadline = time.monotonic() + timeout
    while _stored(db) < n:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, f"fewer than {n} runs after {timeout} s"
        time.sleep(0.05)


@pytest.mark.slow
def test_a_lost_scheduler_stores_no_errors_and_the_same_command_resumes(tmp_path):
    pytest.importorskip("distributed")
    import subprocess
    import time

    cluster = _Cluster(tmp_path)
    try:
        proc, cmd = _bench(tmp_path, "--scheduler", cluster.address)
        try:
            _wait_stored(proc, tmp_path / "s.db", 10)
            cluster.kill(cluster.scheduler)
            t0 = time.monotonic()
            out, err = proc.communicate(timeout=60)
            took = time.monotonic() - t0
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    finally:
        cluster.stop()
    assert proc.returncode == 1, (out, err)
    assert _messages(err) == [
        f"pathfuse bench: error: lost the Dask scheduler at {cluster.address}; the runs "
        "that finished are stored, run the same command again to finish the rest"], err
    assert took < 30, took
    stored = _stored(tmp_path / "s.db")
    assert 10 <= stored < 200
    assert _stored(tmp_path / "s.db", "status_name = 'ERROR'") == 0
    assert f"{stored}/200 in s.db" in out and "errors 0" in out
    # the unfinished runs are missing, not failed: a resumed sweep runs exactly them
    local = [a for a in cmd if a not in ("--scheduler", cluster.address)] + ["--workers", "2"]
    again = subprocess.run(local, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    assert f"{200 - stored} runs" in again.stdout and f"{stored} already stored" in again.stdout
    assert _stored(tmp_path / "s.db", "status_name = 'SUCCESS'") == 200


@pytest.mark.slow
def test_a_cluster_without_workers_says_so_and_stops(tmp_path):
    pytest.importorskip("distributed")
    import time

    cluster = _Cluster(tmp_path)
    try:
        proc, _ = _bench(tmp_path, "--scheduler", cluster.address, "--worker-wait", "8")
        try:
            _wait_stored(proc, tmp_path / "s.db", 10)
            cluster.kill(cluster.worker)  # the scheduler stays, with no worker
            t0 = time.monotonic()
            out, err = proc.communicate(timeout=90)
            took = time.monotonic() - t0
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    finally:
        cluster.stop()
    assert proc.returncode == 1, (out, err)
    assert "Traceback" not in err
    assert _messages(err) == [
        f"pathfuse: no worker is connected to the Dask scheduler at {cluster.address}; "
        "waiting up to 8 s for one (Ctrl-C stops, stored runs are kept)",
        f"pathfuse bench: error: every worker of the Dask cluster at {cluster.address} is "
        "gone (none for 8 s); the runs that finished are stored, start workers and run the "
        "same command again to finish the rest"], err
    assert 8 <= took < 40, took
    assert _stored(tmp_path / "s.db", "status_name = 'ERROR'") == 0
    assert 10 <= _stored(tmp_path / "s.db") < 200
