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
