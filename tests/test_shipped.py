"""The example scenarios and experiment files travel with the package (issue 20, item 4).

A wheel built from this clone carries ``examples/``, ``experiments/`` and the BARN worlds
one example names in ``pathfuse/_shipped/`` (``setup.py``); ``pathfuse examples`` lists
them and every command that reads a scenario or an experiment file takes them by name.
The last test builds the wheel, installs it into a fresh virtual environment outside the
clone and runs ``pathfuse examples`` and ``pathfuse simulate head_on`` from a temporary
folder: the numba kernels of that installation compile cold there (about 70 s of CPU).
"""

from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

from pathfuse import ConfigError
from pathfuse.shipped import SHIPPED_DIRS, copy_examples, examples, resolve, shipped_root

ROOT = Path(__file__).resolve().parents[1]


def _cli(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "pathfuse.cli", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=300)


def test_every_yaml_of_examples_and_experiments_is_listed_by_name():
    on_disk = sorted(p.stem for top in ("examples", "experiments")
                     for p in (ROOT / top).rglob("*.yaml"))
    assert shipped_root() == ROOT  # a clone installed with pip install -e reads itself
    assert sorted(e.name.rsplit("/", 1)[-1] for e in examples()) == on_disk
    kinds = {e.name: e.kind for e in examples()}
    assert kinds["head_on"] == "scenario" and kinds["barn-jackal"] == "experiment"
    assert {e.name for e in examples("experiment")} == {
        p.stem for p in (ROOT / "experiments").glob("*.yaml")}


def test_resolve_keeps_paths_and_finds_names():
    assert resolve("examples/scenarios/crossing.yaml", "scenario") == \
        "examples/scenarios/crossing.yaml" or not (Path.cwd() / "examples").is_dir()
    assert resolve("head_on", "scenario") == str(ROOT / "examples" / "scenarios" / "head_on.yaml")
    assert resolve("head_on.yaml", "scenario").endswith("head_on.yaml")
    assert resolve("scenarios/head_on", "scenario").endswith("head_on.yaml")
    with pytest.raises(ConfigError, match=r"^head_on: no such file, and no shipped experiment "
                       r"of that name \(shipped: any-angle, barn-jackal, .*'pathfuse examples' "
                       r"lists them\)$"):
        resolve("head_on", "experiment")  # a scenario is not an experiment


def test_copy_writes_a_clone_layout_and_never_overwrites(tmp_path):
    written = copy_examples(tmp_path / "ex")
    assert (tmp_path / "ex" / "examples" / "scenarios" / "head_on.yaml") in written
    assert (tmp_path / "ex" / "tests" / "data" / "barn" / "worlds" / "world_17.world.gz") \
        .is_file()
    # the copied scenario's relative map path still works
    from pathfuse.world import load_scenario

    sc = load_scenario(tmp_path / "ex" / "examples" / "scenarios" /
                                      "barn_world_17.yaml")
    assert sc.grid.occupied.any()
    with pytest.raises(ConfigError, match=r"exists already and \d+ more; copy into an empty "
                       r"folder"):
        copy_examples(tmp_path / "ex")


def test_the_examples_command_and_a_shipped_name_on_the_command_line(tmp_path):
    p = _cli("examples")
    assert p.returncode == 0 and "scenario files:" in p.stdout and "experiment files:" in p.stdout
    assert "  head_on  " in p.stdout.replace("head_on   ", "head_on  ")
    bad = _cli("simulate", "no_such_scenario", cwd=tmp_path)
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
    assert "no_such_scenario: no such file, and no shipped scenario of that name (shipped: " \
        "barn_world_17, " in bad.stderr
    bad = _cli("bench", "no_such_experiment", "--db", "x.db", cwd=tmp_path)
    assert bad.returncode == 2 and "no shipped experiment of that name" in bad.stderr
    copied = _cli("examples", "--copy", "mine", cwd=tmp_path)
    assert copied.returncode == 0 and (tmp_path / "mine" / "experiments").is_dir()
    again = _cli("examples", "--copy", "mine", cwd=tmp_path)
    assert again.returncode == 2 and "exists already" in again.stderr


def test_bench_runs_a_shipped_experiment_by_name(tmp_path):
    p = _cli("bench", "fusion-sweep-r1-r2-step", "--db", "s.db", "--seeds", "1", "--workers",
             "1", "--no-progress", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert "fusion-sweep" in p.stdout and (tmp_path / "s.db").is_file()


def test_setup_py_ships_the_same_folders_as_pathfuse_shipped():
    import ast

    tree = ast.parse((ROOT / "setup.py").read_text())
    (value,) = [ast.literal_eval(n.value) for n in tree.body if isinstance(n, ast.Assign)
                and any(getattr(t, "id", "") == "SHIPPED_DIRS" for t in n.targets)]
    assert value == SHIPPED_DIRS


@pytest.mark.slow
def test_a_wheel_installed_outside_the_clone_runs_the_shipped_examples(tmp_path):
    """Build the wheel, install it (no dependencies) into a fresh venv that sees this
    environment's numpy, numba, ... through a .pth line (so the installed pathfuse is the
    wheel's, not this clone's), and run the two commands from a temporary folder."""
    # no PYTHONPATH anywhere: a source tree on it (with the egg-info a build leaves there)
    # would count as an installed pathfuse, and pip would then skip the wheel
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "NUMBA_CACHE_DIR")}
    wheels = tmp_path / "wheels"
    b = subprocess.run([sys.executable, "-m", "pip", "wheel", str(ROOT), "--no-deps", "-q",
                        "-w", str(wheels)], capture_output=True, text=True, timeout=600, env=env)
    assert b.returncode == 0, b.stderr
    (whl,) = wheels.glob("pathfuse-*.whl")
    names = zipfile.ZipFile(whl).namelist()
    for want in ("pathfuse/_shipped/examples/scenarios/head_on.yaml",
                 "pathfuse/_shipped/experiments/barn-jackal.yaml",
                 "pathfuse/_shipped/tests/data/barn/worlds/world_17.world.gz",
                 "pathfuse/datasets/barn.sha256"):
        assert want in names, want
    assert not any(n.startswith("tests/") or "/tests/test_" in n for n in names)
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=300, env=env)
    py = venv / "bin" / "python"
    i = subprocess.run([str(py), "-m", "pip", "install", "-q", "--no-deps", "--no-index",
                        str(whl)], capture_output=True, text=True, timeout=300, env=env)
    assert i.returncode == 0, i.stderr
    site = subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()"
                           "['purelib'])"], capture_output=True, text=True, check=True,
                          env=env).stdout
    # then this environment's dependencies, as plain path entries after the venv's own (its
    # .pth files, among them an editable pathfuse's hook, are not run from there)
    Path(site.strip(), "deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    run_dir = tmp_path / "elsewhere"
    run_dir.mkdir()
    where = subprocess.run([str(py), "-c", "import pathfuse; print(pathfuse.__file__)"],
                           capture_output=True, text=True, cwd=run_dir, env=env)
    assert where.stdout.strip().startswith(str(venv)), where.stderr
    exe = venv / "bin" / "pathfuse"
    ex = subprocess.run([str(exe), "examples"], capture_output=True, text=True, cwd=run_dir,
                        env=env, timeout=120)
    assert ex.returncode == 0 and "head_on" in ex.stdout and "barn-jackal" in ex.stdout, ex.stderr
    sim = subprocess.run([str(exe), "simulate", "head_on", "--json"], capture_output=True,
                         text=True, cwd=run_dir, env=env, timeout=900)
    assert sim.returncode == 0, sim.stderr
    import json

    ep = json.loads(sim.stdout)  # the scenario's own planner, the fusion, passes the disc
    assert ep["status"] == "SUCCESS" and ep["scenario_file"].startswith(str(venv))
