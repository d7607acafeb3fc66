"""Nothing a user types can crash, hang or exhaust pathfuse: the command line (issue 9).

Every case runs ``pathfuse`` in a subprocess under an address-space limit
(``RLIMIT_AS``) and a timeout, and asserts the exact outcome: the exit status, one
line on stderr naming the key or value, no traceback.  Without the checks several of
these cases took gigabytes (a YAML alias bomb 4.4 GB, ``--seeds 0:1000000000`` over
8 GB, ``--robot-radius 1e5`` 17 GB), so the limit turns a regression into a failure
instead of a swapping machine.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"
SANDBOX = DATA / "ros" / "nav2_tb3_sandbox"
MEMORY = 3 * 1024**3          # bytes of address space a case may use (numba needs ~1 GB)
TIMEOUT = 120                 # seconds (a cold numba cache compiles for up to ~20 s)


def _limit_memory() -> None:  # pragma: no cover - runs in the child
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY, MEMORY))


def run(*args, cwd=None, env=None):
    return subprocess.run(
        [sys.executable, "-m", "pathfuse.cli", *map(str, args)], capture_output=True, text=True,
        cwd=cwd, timeout=TIMEOUT, preexec_fn=_limit_memory,
        env=None if env is None else {**os.environ, **env},
    )


def one_line(proc, status, *fragments):
    """The process ended with ``status`` and one stderr line holding every fragment."""
    assert "Traceback" not in proc.stderr, proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()
             and not ln.startswith("pathfuse: compiling")]
    assert len(lines) == 1, proc.stderr
    for f in fragments:
        assert f in lines[0], lines[0]
    assert proc.returncode == status, (proc.returncode, proc.stderr)
    return lines[0]


def bomb() -> str:
    lines = ["l0: &l0 [" + ", ".join(["lol"] * 10) + "]"]
    for i in range(1, 9):
        lines.append(f"l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * 10) + "]")
    return "\n".join(lines) + "\n"


SCENARIO = "map: {rows: ['......', '......', '......']}\nstart: [0.5, 1.5]\ngoal: [5.5, 1.5]\n"


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


# ------------------------------------------------------------------------------------ YAML
def test_alias_bomb_in_a_scenario(tmp_path):
    p = write(tmp_path, "s.yaml", bomb() + SCENARIO + "description: *l8\n")
    one_line(run("simulate", p), 2, "pathfuse simulate: error:", "s.yaml", "MAX_YAML_NODES")


def test_alias_bomb_in_a_map_yaml(tmp_path):
    p = write(tmp_path, "m.yaml", bomb() + "rows: *l8\n")
    one_line(run("plan", "--map", p, "--start", "0.5,0.5", "--goal", "1.5,0.5"), 2,
             "m.yaml", "aliases expanded", "PATHFUSE_MAX_YAML_NODES")


def test_alias_bomb_in_an_experiment(tmp_path):
    p = write(tmp_path, "e.yaml", bomb() + "name: *l8\nmaps: [{name: p, map: paper}]\n"
              "planners: [astar]\n")
    one_line(run("bench", p, "--db", tmp_path / "x.db"), 2, "e.yaml", "MAX_YAML_NODES")
    assert not (tmp_path / "x.db").exists()


def test_deep_nesting_in_an_experiment(tmp_path):
    p = write(tmp_path, "e.yaml", "maps: " + "[" * 20000 + "]" * 20000 + "\n")
    one_line(run("bench", p, "--db", tmp_path / "x.db"), 2, "e.yaml", "line 1",
             "nested deeper than 100 levels")


def test_list_key_in_a_ros_map(tmp_path):
    p = write(tmp_path, "m.yaml", f"image: {SANDBOX / 'tb3_sandbox.pgm'}\n? [1, 2]\n: 3\n")
    one_line(run("plan", "--map", p, "--start", "1,1", "--goal", "2,2"), 2, "m.yaml",
             "a mapping key must be text or a number, got a list")


def test_rows_as_a_string(tmp_path):
    p = write(tmp_path, "r.yaml", 'rows: "......"\n')
    one_line(run("plan", "--map", p, "--start", "0.5,0.5", "--goal", "5.5,0.5"), 2,
             "r.yaml", "'rows' must be a list of strings")


@pytest.mark.parametrize("value", ["1e-2", "1E-2", "0.01", ".01"])
def test_param_floats_as_typed(value):
    p = run("plan", "--map", "paper", "--planner", "fusion", "--param", f"step_m={value}",
            "--json")
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    # moves of 0.01 m (the default is 0.5 m): as many moves as centimetres of path
    assert d["status"] == "SUCCESS"
    assert d["iterations"] >= 0.99 * d["length"] / 0.01


# ------------------------------------------------------------------------------------ limits
def test_seeds_of_a_sweep(tmp_path):
    exp = ROOT / "experiments" / "fusion-sweep-r1-r2-step.yaml"
    one_line(run("bench", exp, "--db", tmp_path / "x.db", "--seeds", "0:1000000000"), 2,
             "seeds (override): a seed count: 1000000000 is above the limit of 2000000",
             "PATHFUSE_MAX_RUNS")
    p = write(tmp_path, "e.yaml", "seeds: 1000000000\nmaps: [{name: p, map: paper}]\n"
              "planners: [astar]\n")
    one_line(run("bench", p, "--db", tmp_path / "y.db"), 2, "e.yaml: seeds: a seed count")


def test_seed_too_large_for_the_store(tmp_path):
    p = write(tmp_path, "e.yaml", "seeds: [100000000000000000000000]\n"
              "maps: [{name: p, map: paper}]\nplanners: [astar]\n")
    one_line(run("bench", p, "--db", tmp_path / "x.db"), 2,
             "seeds[0]: a seed must be an integer in [0, 2**63)")


def test_parameter_grid(tmp_path):
    axis = lambda n, s: "[" + ", ".join(str(s * (i + 1)) for i in range(n)) + "]"  # noqa: E731
    p = write(tmp_path, "e.yaml", "maps: [{name: p, map: paper}]\nplanners:\n"
              "  - name: fusion\n    params:\n"
              f"      r1_m: {axis(1000, 0.01)}\n      r2_m: {axis(1000, 0.01)}\n"
              f"      step_m: {axis(100, 0.001)}\n")
    one_line(run("bench", p, "--db", tmp_path / "x.db"), 2,
             "the parameter grid (1000 x 1000 x 100): 100000000 is above the limit")


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_map_linked_to_dev_zero(tmp_path):
    (tmp_path / "zero.map").symlink_to("/dev/zero")
    one_line(run("plan", "--map", tmp_path / "zero.map", "--start", "1,1", "--goal", "2,2"), 2,
             "zero.map: the map file is a device, not a file")


def test_map_larger_than_the_file_limit(tmp_path):
    p = write(tmp_path, "big.map", "type octile\nheight 1\nwidth 4000\nmap\n" + "." * 4000 + "\n")
    one_line(run("plan", "--map", p, "--start", "1,0.5", "--goal", "2,0.5",
                 env={"PATHFUSE_MAX_FILE_BYTES": "1000"}), 2,
             "big.map: the map file is larger than the limit of 1000 bytes",
             "PATHFUSE_MAX_FILE_BYTES")


def test_movingai_header_of_width_1e9(tmp_path):
    p = write(tmp_path, "wide.map", "type octile\nheight 3\nwidth 1000000000\nmap\n...\n...\n"
              "...\n")
    one_line(run("plan", "--map", p, "--start", "1,1", "--goal", "2,2"), 2,
             "wide.map", "3 x 1000000000 = 3000000000 cells", "PATHFUSE_MAX_CELLS")


def test_limit_raised_by_the_environment(tmp_path):
    p = write(tmp_path, "e.yaml", "seeds: 5\nmaps: [{name: p, map: paper}]\nplanners: [astar]\n")
    one_line(run("bench", p, "--db", tmp_path / "x.db", env={"PATHFUSE_MAX_RUNS": "3"}), 2,
             "a seed count: 5 is above the limit of 3")


@pytest.mark.parametrize("extra, fragment", [
    ("time_limit: 1e6\n", "1e+07 ticks"), ("dt: 1e-9\n", "6e+10 ticks")])
def test_episode_ticks(tmp_path, extra, fragment):
    p = write(tmp_path, "s.yaml", SCENARIO + extra)
    one_line(run("simulate", p), 2, "s.yaml: time_limit / dt", fragment, "PATHFUSE_MAX_TICKS")


def test_huge_robot_radius():
    p = run("plan", "--map", "paper", "--robot-radius", "1e5")
    assert p.returncode == 1 and "Traceback" not in p.stderr
    assert "START_OCCUPIED" in p.stdout and "overlaps the map's edge" in p.stdout


def test_random_map_of_1e14_cells(tmp_path):
    p = write(tmp_path, "s.yaml", "map: {random: {size: [1e7, 1e7], obstacles: 1}}\n"
              "start: [0.5, 0.5]\ngoal: [2.5, 0.5]\n")
    one_line(run("simulate", p), 2, "s.yaml", "10000000 x 10000000", "MAX_CELLS")


def test_tiny_step():
    one_line(run("plan", "--map", "paper", "--planner", "apf", "--param", "step_m=1e-300"), 2,
             "step_m: a step of 1e-300 m", "MAX_STEPS")


# ------------------------------------------------------------------ smaller ones (item 10)
def test_ros_yaw_warning_is_one_line(tmp_path):
    text = (SANDBOX / "tb3_sandbox.yaml").read_text().replace("0.000000]", "0.5]")
    text = text.replace("image: tb3_sandbox.pgm", f"image: {SANDBOX / 'tb3_sandbox.pgm'}")
    p = write(tmp_path, "yaw.yaml", text)
    proc = run("plan", "--map", p, "--start=-1.0,-0.5", "--goal", "1.5,0.5")
    assert proc.returncode == 0
    line = one_line(proc, 0, "pathfuse plan: warning:", "yaw 0.5 rad is not applied")
    assert "UserWarning" not in line and ".py" not in line


def test_scen_with_only_a_header(tmp_path):
    p = write(tmp_path, "e.scen", "version 1\n")
    proc = run("scen", DATA / "movingai" / "den312d.map", p)
    one_line(proc, 2, "e.scen: scenario file holds no problem line")
    assert "0/0" not in proc.stdout


def test_scen_arguments_swapped():
    proc = run("scen", DATA / "movingai" / "den312d.map.scen", DATA / "movingai" / "den312d.map")
    one_line(proc, 2, "must be the header 'type octile', got 'version 1'",
             "this is a MovingAI scenario file (.scen), not a map: give the .map first")


def test_plot_into_a_folder(tmp_path):
    (tmp_path / "out").mkdir()
    one_line(run("plan", "--map", "paper", "--plot", "out", cwd=tmp_path), 2,
             "--plot: out is a folder; give a file name such as out/plan.png")
    assert not (tmp_path / "out.png").exists()


def test_plot_without_a_suffix(tmp_path):
    proc = run("plan", "--map", "paper", "--plot", "fig", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "figure    fig.png" in proc.stdout and (tmp_path / "fig.png").is_file()


def test_plot_into_a_missing_folder():
    one_line(run("plan", "--map", "paper", "--plot", "/nonexistent/dir/p.png"), 2,
             "--plot: the folder /nonexistent/dir does not exist")


def test_goal_in_unknown_space():
    proc = run("plan", "--map", SANDBOX / "tb3_sandbox.yaml", "--start=-1.0,-0.5",
               "--goal=-9.975,-9.975")
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    assert "GOAL_OCCUPIED" in proc.stdout and "lies in an unknown cell" in proc.stdout
    proc = run("plan", "--map", SANDBOX / "tb3_sandbox.yaml", "--start=-1.0,-0.5",
               "--goal=-9.975,-9.975", "--unknown", "free")
    assert "NO_PATH" in proc.stdout


def test_bench_names_the_modules_it_imports(tmp_path):
    write(tmp_path, "plug.py", "X = 1\n")
    p = write(tmp_path, "e.yaml", "imports: [plug.py, json]\nmaps: [{name: p, map: paper}]\n"
              "planners: [astar]\n")
    proc = run("bench", p, "--db", tmp_path / "x.db", "--workers", "1", "--no-progress")
    assert proc.returncode == 0, proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if "importing" in ln]
    assert lines == ["pathfuse bench: importing plug.py, json (the experiment file's "
                     "'imports:' runs this code)"]


def test_os_error_names_the_file(tmp_path):
    (tmp_path / "ro").mkdir()
    (tmp_path / "ro").chmod(0o500)
    if os.access(tmp_path / "ro", os.W_OK):  # root ignores permissions
        pytest.skip("running as root")
    one_line(run("plan", "--map", "paper", "--plot", tmp_path / "ro" / "p.png"), 2,
             f"{tmp_path / 'ro' / 'p.png'}: Permission denied")


def test_dynamic_with_too_many_discs(tmp_path):
    proc = run("dynamic", "--moving", "100000", "--seeds", "1", "--out", tmp_path / "d")
    one_line(proc, 2, "moving: 100000 moving discs", "6e+07 body-ticks", "MAX_TICKS")
    assert not (tmp_path / "d").exists()      # refused before any folder or database
