"""The command line, end to end through a subprocess, as a user runs it."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

DATA = Path(__file__).parent / "data"


def run(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "pathfuse.cli", *map(str, args)],
        capture_output=True, text=True, cwd=cwd, timeout=300,
    )


def assert_one_line_error(proc, *fragments):
    assert proc.returncode != 0
    assert "Traceback" not in proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, proc.stderr
    for f in fragments:
        assert f in lines[0], lines[0]


def test_help_of_every_command_shows_an_example():
    top = run("--help")
    assert top.returncode == 0 and "examples:" in top.stdout
    for cmd in ("plan", "scen", "planners", "paper", "simulate", "dynamic", "bench", "report"):
        p = run(cmd, "--help")
        assert p.returncode == 0, p.stderr
        assert "example" in p.stdout and f"pathfuse {cmd}" in p.stdout


def test_plan_paper_map_json_and_plot(tmp_path):
    png = tmp_path / "plan.png"
    p = run("plan", "--map", "paper", "--seed", "3", "--json", "--plot", png)
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    assert d["status"] == "SUCCESS" and d["planner"] == "astar"
    assert d["path"][0] == [1.0, 1.0] and d["path"][-1] == [11.0, 11.0]
    assert d["map"].startswith("paper")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plan_movingai_map_matches_scen_line():
    from pathfuse.io import read_movingai, read_scen

    m = DATA / "movingai" / "den312d.map"
    grid = read_movingai(m)
    prob = read_scen(DATA / "movingai" / "den312d.map.scen", grid)[-1]
    p = run("plan", "--map", m, "--start", "{},{}".format(*prob.start),
            "--goal", "{},{}".format(*prob.goal), "--json")
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout)["length"] == pytest.approx(prob.optimal_length, rel=1e-9)


def test_plan_reports_failure_status_with_exit_1():
    p = run("plan", "--map", "paper", "--start", "1,1", "--goal", "20,20")
    assert p.returncode == 1
    assert "GOAL_OUT_OF_BOUNDS" in p.stdout


@pytest.mark.parametrize(
    "args, fragments",
    [
        (["plan", "--map", "nope.map", "--start", "1,1", "--goal", "2,2"], ["nope.map"]),
        (["plan", "--map", "paper", "--start", "1;x", "--goal", "2,2"], ["--start"]),
        (["plan", "--map", "paper", "--start", "nan,1", "--goal", "2,2"], ["--start"]),
        (["plan", "--map", "paper", "--planner", "dijkstra"], ["dijkstra"]),
        (["plan", "--map", "paper", "--param", "heuristic=manhattan"], ["manhattan"]),
        (["plan", "--map", "paper", "--param", "bogus=1"], ["bogus"]),
        (["plan", "--map", "paper", "--resolution", "abc"], ["--resolution"]),
        (["scen", DATA / "movingai" / "den312d.map", "missing.scen"], ["missing.scen"]),
        (["paper", "--seeds", "0"], ["--seeds"]),
        (["paper", "--variant", "matlab"], ["--variant", "matlab"]),
    ],
)
def test_bad_input_is_one_line_and_nonzero(args, fragments):
    assert_one_line_error(run(*args), *fragments)


def test_truncated_map_file_is_one_line_error(tmp_path):
    src = (DATA / "movingai" / "den312d.map").read_text().splitlines()
    bad = tmp_path / "cut.map"
    bad.write_text("\n".join(src[:20]) + "\n")
    assert_one_line_error(run("plan", "--map", bad, "--start", "1,1", "--goal", "2,2"), "cut.map")


def test_scen_counts_matches_and_fails_on_mismatch(tmp_path):
    m = DATA / "movingai" / "maze-32-32-2.map"
    s = DATA / "movingai" / "maze-32-32-2-random-1.scen"
    ok = run("scen", m, s)
    assert ok.returncode == 0, ok.stdout + ok.stderr
    n = len(s.read_text().splitlines()) - 1
    assert f"{n}/{n} lines match" in ok.stdout
    # corrupt one optimal length: the command must say so and exit 1
    lines = s.read_text().splitlines()
    cols = lines[5].split("\t")
    cols[-1] = f"{float(cols[-1]) + 1.0:.8f}"
    lines[5] = "\t".join(cols)
    bad = tmp_path / "bad.scen"
    bad.write_text("\n".join(lines) + "\n")
    p = run("scen", m, bad, "--limit", "10")
    assert p.returncode == 1
    assert "9/10 lines match" in p.stdout and "line 6" in p.stdout


def test_planners_lists_the_registry():
    from pathfuse.planners.registry import controller_names, global_planner_names, planner_names

    p = run("planners", "--json")
    assert p.returncode == 0
    d = json.loads(p.stdout)
    assert list(d["planners"]) == planner_names()
    assert list(d["global_planners"]) == global_planner_names()
    assert list(d["controllers"]) == controller_names()
    assert d["planners"]["thetastar"]["controller"] == "follow"
    assert "thetastar" in d["controllers"]["follow"]["planners"]
    text = run("planners").stdout
    assert "\nglobal planners" in text and "\njps\n  jump point search" in text
    assert "\nfusion  (Algorithm 2): planners fusion" in text


def test_global_planner_option(tmp_path):
    p = run("plan", "--map", "paper", "--planner", "fusion", "--global-planner", "thetastar",
            "--json")
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    assert d["global_planner"] == "thetastar" and d["status"] == "SUCCESS"
    a = json.loads(run("plan", "--map", "paper", "--planner", "fusion", "--json").stdout)
    assert a["global_planner"] == "astar" and a["path"] != d["path"]
    p = run("plan", "--map", "paper", "--planner", "fusion", "--global-planner", "nope")
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr.strip().splitlines() == [
        "pathfuse plan: error: fusion.global_planner: must be one of astar, jps, astar-smooth, "
        "thetastar, lazy-thetastar, shortest, got 'nope'"]
    p = run("plan", "--map", "paper", "--planner", "fusion", "--global-planner", "jps",
            "--param", "global_planner=astar")
    assert p.returncode != 0 and "disagree" in p.stderr


def test_negative_coordinates_are_accepted_on_a_ros_map():
    yaml_path = DATA / "ros" / "nav2_tb3_sandbox" / "tb3_sandbox.yaml"
    p = run("plan", "--map", yaml_path, "--start", "-1.01,-0.51", "--goal", "1.5,0.5",
            "--robot-radius", "0.1", "--json")
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    assert d["status"] == "SUCCESS"
    assert d["path"][0] == pytest.approx([-1.025, -0.525])  # centre of the start cell


def test_paper_variant_and_corner_cutting(tmp_path):
    out = tmp_path / "p"
    p = run("paper", "--seeds", "3", "--variant", "paper", "--corner-cutting", "--workers", "1",
            "--out", out, "--quiet")
    assert p.returncode == 0, p.stderr
    assert "fusion/paper" in p.stdout and "shortest" in p.stdout
    # the fusion as printed fails on all three maps: its empty statistics read n/a, not nan
    row = next(x for x in p.stdout.splitlines() if "fusion/paper" in x).split()
    assert row[2:4] == ["0/3", "n/a"], row
    md = (out / "tables.md").read_text()
    assert "paper variant: path length" in md and "pathfuse variant" not in md
    assert "nan" not in p.stdout.lower() and " nan " not in md
    assert "A-star (corner cutting)" in md and "with corner cutting" in md
    assert "Excess over the shortest path" in md
    p = run("paper", "--seeds", "2", "--variant", "pathfuse", "--no-references", "--workers",
            "1", "--out", tmp_path / "q", "--quiet")
    assert p.returncode == 0, p.stderr
    md = (tmp_path / "q" / "tables.md").read_text()
    assert "Theta*" not in md and "Excess" not in md and "fusion/paper" not in md


def test_paper_headline_says_how_many_ran_in_plain_words(tmp_path):
    import re

    out = tmp_path / "p"
    args = ("paper", "--seeds", "2", "--variant", "pathfuse", "--no-references", "--workers",
            "1", "--out", out, "--quiet")
    p = run(*args)
    assert p.returncode == 0, p.stderr
    first = p.stdout.splitlines()[0]
    assert re.fullmatch(r"(\d+) runs on 2 maps in \d+\.\d\d s \(\d+ runs/s, 1 worker"
                        r"(, [\d.]+ s of it compiling kernels)?\)", first), first
    n = int(first.split()[0])
    again = run(*args).stdout.splitlines()[0]  # the same command: every run is stored
    assert again == f"{n} runs on 2 maps, all already in {out / 'study.db'}"
    assert "run now" not in p.stdout + again

