"""What a new user sees while a command works: one progress display for bench, paper, dynamic
and scen (a live bar on a terminal, a few plain lines otherwise), and a notice before a
first, slow compile."""

from __future__ import annotations

import io
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pathfuse.bench.progress import ProgressBar

DATA = Path(__file__).resolve().parent / "data" / "movingai"
MAP, SCEN = DATA / "den312d.map", DATA / "den312d.map.scen"

TINY = """
name: tiny
seeds: 2
maps: [paper]
planners: [astar]
"""

COMMANDS = {
    "bench": (["bench", "tiny.yaml", "--db", "t.db", "--workers", "1"], "tiny [", "runs/s"),
    "paper": (["paper", "--seeds", "2", "--workers", "1", "--out", "p"], "paper [", "runs/s"),
    "dynamic": (["dynamic", "--seeds", "1", "--moving", "0", "--planners", "astar",
                 "--workers", "1", "--out", "d"], "dynamic [", "episodes/s"),
    "scen": (["scen", str(MAP), str(SCEN), "--limit", "200"], "den312d.map.scen [",
             "lines/s"),
}


def run(args, cwd, env=None, stderr_tty=False):
    cmd = [sys.executable, "-m", "pathfuse.cli", *args]
    if not stderr_tty:
        p = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=600, env=env)
        return p.returncode, p.stderr
    import pty

    master, slave = pty.openpty()
    try:
        proc = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.DEVNULL, stderr=slave,
                                env=env)
        os.close(slave)
        chunks = []
        while True:
            try:
                data = os.read(master, 4096)
            except OSError:  # the child closed the terminal
                break
            if not data:
                break
            chunks.append(data)
        code = proc.wait(timeout=600)
    finally:
        os.close(master)
    return code, b"".join(chunks).decode()


@pytest.mark.parametrize("name", list(COMMANDS))
def test_off_a_terminal_every_command_writes_a_few_plain_lines(tmp_path, name):
    args, head, unit = COMMANDS[name]
    (tmp_path / "tiny.yaml").write_text(TINY)
    code, err = run(args, tmp_path)
    assert code == 0, err
    assert "\r" not in err and "\x1b[" not in err
    lines = [ln for ln in err.splitlines() if not ln.startswith("pathfuse: compiling")]
    assert len(lines) == 1, err  # a short task: its last line only
    assert lines[0].startswith(head) and " 100%" in lines[0]
    assert unit in lines[0] and "  in 0:00:" in lines[0]


@pytest.mark.parametrize("name", ["bench", "scen"])
def test_on_a_terminal_the_bar_is_redrawn_in_place(tmp_path, name):
    args, head, unit = COMMANDS[name]
    (tmp_path / "tiny.yaml").write_text(TINY)
    code, err = run(args, tmp_path, stderr_tty=True)
    assert code == 0, err
    frames = [f for f in err.replace("\r\n", "\n").split("\r") if f.strip()]
    assert len(frames) >= 2 and all(f.startswith(head) for f in frames), frames
    assert "\x1b[K" in err and frames[-1].rstrip("\n").endswith("\x1b[K")
    assert " 100%" in frames[-1] and unit in frames[-1] and "  in 0:00:" in frames[-1]


def test_quiet_shows_nothing(tmp_path):
    (tmp_path / "tiny.yaml").write_text(TINY)
    for args in (["bench", "tiny.yaml", "--db", "t.db", "--workers", "1", "--no-progress"],
                 ["scen", str(MAP), str(SCEN), "--limit", "50", "--quiet"]):
        code, err = run(args, tmp_path)
        assert code == 0 and err == "", err


@pytest.mark.slow
@pytest.mark.parametrize("args, what", [
    (["bench", "tiny.yaml", "--db", "t.db", "--workers", "1"], "astar and the metrics"),
    (["scen", str(MAP), str(SCEN), "--limit", "5"], "astar"),
])
def test_a_cold_first_run_says_it_compiles_before_it_waits(tmp_path, args, what):
    """On an empty numba cache the first line, before any wait, says what is compiled."""
    (tmp_path / "tiny.yaml").write_text(TINY)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cold-cache")}
    code, err = run(args, tmp_path, env=env)
    assert code == 0, err
    first = err.splitlines()[0]
    assert first == (f"pathfuse: compiling the kernels of {what} (first run only; cached "
                     "afterwards)"), err
    assert err.count("pathfuse: compiling") == 1
    code, err = run(args, tmp_path, env=env)  # warm now: no notice
    assert code == 0 and "compiling" not in err


def test_rate_and_eta_wait_for_the_first_results():
    """Start-up (workers, kernels) does not count: no "0.0 runs/s ETA 1:48:13" at first."""
    out = io.StringIO()
    bar = ProgressBar(100, label="s", stream=out, tty=False, interval_s=0.0)
    time.sleep(0.2)  # a slow start
    bar.update(1)
    assert bar.line().endswith("starting")
    time.sleep(0.05)
    bar.update(9)
    rate = bar.rate(time.perf_counter())
    assert rate is not None and rate > 9 / 0.2  # measured from the first result on
    assert "runs/s  ETA 0:00:" in bar.line()
    bar.notice("a worker joined")
    bar.close()
    lines = out.getvalue().splitlines()
    assert "pathfuse: a worker joined" in lines
    assert lines[-1].startswith("s [") and "10/100" in lines[-1] and "  in 0:00:00" in lines[-1]
