"""`pathfuse simulate` and `pathfuse dynamic`, end to end through a subprocess."""

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from PIL import Image

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "scenarios"
HEAD_ON = EXAMPLES / "head_on.yaml"


def run(*args, env=None, cwd=None):
    return subprocess.run([sys.executable, "-m", "pathfuse.cli", *map(str, args)],
                          capture_output=True, text=True, env=env, cwd=cwd, timeout=300)


def assert_one_line_error(proc, *fragments, code=2):
    assert proc.returncode == code, (proc.returncode, proc.stdout, proc.stderr)
    assert "Traceback" not in proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, proc.stderr
    for f in fragments:
        assert f in lines[0], lines[0]


def test_help_shows_examples():
    top = run("--help")
    assert "pathfuse simulate" in top.stdout and "pathfuse dynamic" in top.stdout
    for cmd in ("simulate", "dynamic"):
        p = run(cmd, "--help")
        assert p.returncode == 0, p.stderr
        assert "examples:" in p.stdout and f"pathfuse {cmd} " in p.stdout


def test_simulate_json_equals_the_library(tmp_path):
    from pathfuse import simulate

    p = run("simulate", HEAD_ON, "--json")
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    ep = simulate(HEAD_ON).to_dict(trajectories=False)
    for k in ("status", "planner", "params", "path_length_m", "time_to_goal_s",
              "min_distance_m", "n_ticks", "collision_with"):
        assert d[k] == ep[k], k
    assert d["status"] == "SUCCESS" and "positions" not in d
    full = json.loads(run("simulate", HEAD_ON, "--json", "--trajectories").stdout)
    assert len(full["positions"]) == full["n_ticks"] + 1


def test_simulate_collision_exits_1_and_writes_the_gif(tmp_path):
    gif = tmp_path / "head_on.gif"
    p = run("simulate", HEAD_ON, "--planner", "astar-follow", "--gif", gif, "--frame-step", "4",
            "--json")
    assert p.returncode == 1, p.stderr  # a failure outcome
    d = json.loads(p.stdout)
    assert d["status"] == "COLLISION" and d["collision_with"] == 0
    n, step = d["n_ticks"], 4
    expected = len(range(0, n + 1, step)) + (1 if n % step else 0)
    assert d["animation"]["frames"] == expected == Image.open(gif).n_frames
    # the human summary
    h = run("simulate", HEAD_ON, "--planner", "astar-follow")
    assert h.returncode == 1
    for word in ("COLLISION", "to goal", "path", "distance", "ticks", "us/tick"):
        assert word in h.stdout


def test_simulate_params_and_seed(tmp_path):
    a = json.loads(run("simulate", EXAMPLES / "random_walkers.yaml", "--seed", "3",
                       "--planner", "fusion", "--param", "swerve=0", "--json").stdout)
    assert a["params"]["swerve"] == 0 and a["seed"] == 3
    b = json.loads(run("simulate", EXAMPLES / "random_walkers.yaml", "--seed", "3",
                       "--planner", "fusion", "--param", "swerve=0", "--json").stdout)
    assert a == {**b, "setup_time_s": a["setup_time_s"], "mean_plan_time_s":
                 a["mean_plan_time_s"], "max_plan_time_s": a["max_plan_time_s"]}


def test_dynamic_end_to_end(tmp_path):
    out = tmp_path / "dyn"
    p = run("dynamic", "--seeds", "3", "--moving", "0", "2", "--planners",
            "fusion,astar-follow", "--speed", "0.4,0.9", "--seed", "5", "--out", out)
    assert p.returncode == 0, p.stderr
    assert "12 episodes" in p.stdout and "episodes/s" in p.stdout
    # like every command, off a terminal the progress display is a few plain lines: here,
    # a short study, its last line only (after a compile notice on a cold numba cache)
    bars = [ln for ln in p.stderr.splitlines() if not ln.startswith("pathfuse: compiling")]
    assert len(bars) == 1 and "\r" not in p.stderr, p.stderr
    assert bars[0].startswith("dynamic [") and " 12/12 100%" in bars[0]
    assert "episodes/s  in 0:00:" in bars[0]
    for name in ("dynamic.md", "summary.csv", "episodes.csv", "success_vs_moving.png"):
        assert (out / name).is_file(), name
    with open(out / "episodes.csv", newline="") as fh:
        eps = list(csv.DictReader(fh))
    assert len(eps) == 12
    assert {(e["moving"], e["planner"]) for e in eps} == {
        (m, pl) for m in ("0", "2") for pl in ("fusion", "astar")}
    with open(out / "summary.csv", newline="") as fh:
        summ = list(csv.DictReader(fh))
    for r in summ:
        n = sum(int(r[k]) for k in ("reached", "collision", "timeout", "local_minimum",
                                    "no_path"))
        assert n == int(r["episodes"]) == 3
        mine = [e for e in eps if (e["moving"], e["planner"]) == (r["moving"], r["planner"])]
        assert int(r["reached"]) == sum(e["status"] == "SUCCESS" for e in mine)


def _bad_scenario(tmp_path):
    f = tmp_path / "bad.yaml"
    f.write_text(HEAD_ON.read_text().replace("robot: {radius: 0.2,", "robot: {size: 0.2,"))
    return f


@pytest.mark.parametrize("args,fragments", [
    (("simulate", "no-such-file.yaml"), ("simulate", "no-such-file.yaml")),
    (("simulate", "BAD"), ("robot.size", "unknown key")),
    (("simulate", HEAD_ON, "--planner", "nope"), ("unknown planner 'nope'",)),
    (("simulate", HEAD_ON, "--param", "kat=1"), ("kat", "unknown parameter")),
    (("simulate", HEAD_ON, "--seed", "-1"), ("--seed",)),
    (("simulate", HEAD_ON, "--fps", "0"), ("--fps",)),
    (("simulate", HEAD_ON, "--gif", "a.gif", "--mp4", "b.mp4"), ("--mp4",)),
    (("simulate", HEAD_ON, "--gif", "no-such-dir/a.gif"), ("--gif", "no-such-dir", "exist")),
    (("dynamic", "--planners", "fusion,nope"), ("planners", "'nope'")),
    (("dynamic", "--planners", ","), ("--planners",)),
    (("dynamic", "--speed", "fast"), ("--speed", "'fast'")),
    (("dynamic", "--speed", "0.8,0.3"), ("--speed", "0 < MIN <= MAX")),
    (("dynamic", "--speed", "0,1"), ("--speed",)),
    (("dynamic", "--speed", "1,2,3"), ("--speed",)),
    (("dynamic", "--moving", "-1"), ("--moving",)),
    (("dynamic", "--seeds", "0"), ("--seeds",)),
    (("dynamic", "--param", "swerve=0"), ("PLANNER.KEY=VALUE",)),
    (("dynamic", "--param", "fusion.kat=1"), ("params.fusion.kat",)),
    (("dynamic", "--planners", "apf", "--param", "fusion.swerve=0"), ("params.fusion",)),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, monkeypatch, capsys, args, fragments):
    """In process (fast): main() must return 2 / exit 2 with one stderr line, raising nothing."""
    from pathfuse.cli import main

    monkeypatch.chdir(tmp_path)
    args = [str(_bad_scenario(tmp_path) if a == "BAD" else a) for a in args]
    try:
        code = main(args)
    except SystemExit as exc:  # argparse's own errors
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    for f in fragments:
        assert f in lines[0], lines[0]
    assert not list(tmp_path.glob("*.gif")) and not (tmp_path / "dynamic-out").exists()


@pytest.mark.parametrize("args,fragments", [
    (("simulate", "no-such-file.yaml"), ("no-such-file.yaml",)),
    (("dynamic", "--speed", "0.8,0.3"), ("--speed",)),
    (("dynamic", "--planners", "nope"), ("'nope'",)),
])
def test_bad_input_through_a_subprocess(tmp_path, args, fragments):
    assert_one_line_error(run(*args, cwd=tmp_path), *fragments)


def test_mp4_without_ffmpeg_on_path(tmp_path):
    env = dict(os.environ, PATH=str(tmp_path / "empty-bin"))
    out = tmp_path / "x.mp4"
    p = run("simulate", HEAD_ON, "--mp4", out, env=env)
    assert_one_line_error(p, "ffmpeg", "not found", "--gif")
    assert not out.exists()
