"""Global planners and controllers as plug-ins (issue 20, item 1).

The example plug-in package ``examples/plugin`` is put on the path with a
``.dist-info`` folder holding its entry point, as ``pip install`` would leave
it, so that :mod:`importlib.metadata` finds it; pathfuse must load it on the
first use of its registry, list it, and let the path followers, the fusion and
dwa follow its global path.
"""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import pathfuse
from pathfuse import ConfigError, GridMap, Status, plan
from pathfuse.planners import registry
from pathfuse.planners.globals.builtin import run_global
from pathfuse.problem import Problem

ROOT = Path(__file__).resolve().parents[1]
PLUGIN = ROOT / "examples" / "plugin"

ROOM = GridMap.from_rows([
    "..........",
    "..####....",
    ".....#....",
    ".....#....",
    "..........",
])
START, GOAL = (0.5, 0.5), (8.5, 3.5)


def _site(tmp: Path, entry_points: str, name: str = "pathfuse_plugin_example") -> Path:
    """A folder with the dist-info of an installed distribution declaring ``entry_points``."""
    site = tmp / "site"
    info = site / f"{name}-0.1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 0.1.0\n")
    (info / "entry_points.txt").write_text(entry_points)
    return site


def _entry_points_of_example() -> str:
    """The example package's entry points, as its own pyproject.toml declares them (the
    lines of its ``[project.entry-points."pathfuse.planners"]`` table)."""
    text = (PLUGIN / "pyproject.toml").read_text()
    table = text.split('[project.entry-points."pathfuse.planners"]\n', 1)[1].split("\n[", 1)[0]
    lines = [ln.replace('"', "") for ln in table.splitlines() if "=" in ln]
    assert lines == ["bfs4 = pathfuse_plugin_example:register"]
    return "[pathfuse.planners]\n" + "".join(f"{ln}\n" for ln in lines)


@pytest.fixture
def fresh_plugins(monkeypatch):
    """Let :func:`registry.load_plugins` run again on this test's path (conftest.py gives
    the registry back afterwards)."""
    registry._load_builtin()
    monkeypatch.setattr(registry, "_PLUGINS_DONE", [])
    return monkeypatch


@pytest.fixture
def example(tmp_path, fresh_plugins):
    site = _site(tmp_path, _entry_points_of_example())
    fresh_plugins.syspath_prepend(str(PLUGIN / "src"))
    fresh_plugins.syspath_prepend(str(site))
    assert registry.load_plugins() == ["bfs4"]
    return site


def _bfs_path() -> np.ndarray:
    from pathfuse_plugin_example import bfs4

    return bfs4(Problem.create(ROOM, START, GOAL))


def test_the_example_registers_a_global_planner_and_a_planner(example):
    assert "bfs4" in pathfuse.global_planner_names() and "bfs4" in pathfuse.planner_names()
    assert registry.get_global_planner("bfs4").plugin == "bfs4"
    path = _bfs_path()
    # 4-connected: every move between cell centres is one straight cell
    steps = np.abs(np.diff(path[1:-1], axis=0)).sum(axis=1)
    assert np.allclose(steps, 1.0)
    r = plan(ROOM, START, GOAL, planner="bfs4")
    assert r.status is Status.SUCCESS and np.array_equal(r.path, path)
    assert r.length == pytest.approx(float(np.hypot(*np.diff(path, axis=0).T).sum()))
    assert r.info["global_planner"] == "bfs4"


@pytest.mark.parametrize("planner", ["astar", "fusion", "dwa", "ref6"])
def test_the_controllers_follow_the_plugin_path(example, planner):
    path = _bfs_path()
    r = plan(ROOM, START, GOAL, planner=planner, global_planner="bfs4", robot_radius_m=0.1)
    assert r.status is Status.SUCCESS, r.message
    followed = r.path if planner == "astar" else r.info["astar_path"]
    assert np.array_equal(followed, path)
    if planner != "astar":
        assert r.info["global_planner"] == "bfs4"
        # the controller's own path stays near the plug-in's (it is what it follows)
        gap = np.hypot(r.path[:, None, 0] - path[None, :, 0],
                       r.path[:, None, 1] - path[None, :, 1]).min(axis=1)
        assert gap.max() < 1.5
    assert r.info["min_clearance_m"] > 0


def test_the_plugin_path_differs_from_astar(example):
    a = plan(ROOM, START, GOAL, planner="fusion")
    b = plan(ROOM, START, GOAL, planner="fusion", global_planner="bfs4")
    assert a.info["astar_length"] < b.info["astar_length"]  # A* takes diagonals
    assert not np.array_equal(a.path, b.path)


def test_simulate_follows_the_plugin_path(example):
    doc = {"map": {"rows": ["." * 12] * 4 + ["...####....."] + ["." * 12] * 2},
           "start": [0.5, 0.5], "goal": [11.5, 6.5], "robot": {"radius": 0.2}}
    ep = pathfuse.simulate(doc, planner={"name": "astar", "params": {"global_planner": "bfs4"}})
    assert ep.status is Status.SUCCESS, ep.message
    first = ep.path_updates[0][1]
    steps = np.abs(np.diff(first[1:-1], axis=0)).sum(axis=1)
    assert np.allclose(steps, 1.0)  # the 4-connected path was walked


def test_cli_lists_and_plans_with_the_plugin(tmp_path):
    site = _site(tmp_path, _entry_points_of_example())
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT / "src"), str(PLUGIN / "src"), str(site)])}
    cmd = [sys.executable, "-m", "pathfuse.cli"]
    p = subprocess.run([*cmd, "planners"], env=env, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert "bfs4  [plug-in bfs4]" in p.stdout and "\nbfs4  (global planner: bfs4" in p.stdout
    p = subprocess.run([*cmd, "plan", "--map", "paper", "--planner", "fusion",
                        "--global-planner", "bfs4", "--json"], env=env, capture_output=True,
                       text=True)
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    assert d["status"] == "SUCCESS" and d["global_planner"] == "bfs4"
    p = subprocess.run([*cmd, "plan", "--map", "paper", "--planner", "bfs4", "--json"], env=env,
                       capture_output=True, text=True)
    path = np.array(json.loads(p.stdout)["path"])
    assert np.allclose(np.abs(np.diff(path[1:-1], axis=0)).sum(axis=1), 1.0)  # 4-connected


def test_a_builtin_name_loads_every_builtin_before_a_plugin(tmp_path):
    """Without a plug-in a look-up of a built-in planner imports its module alone; with one
    installed (it may replace a built-in name) every built-in module is imported first and
    the plug-ins after them, as on any other first use of the registry."""
    site = _site(tmp_path, _entry_points_of_example())
    code = ("import sys\n"
            "from pathfuse.planners import registry\n"
            "registry.get_planner('astar')\n"
            "print('pathfuse.planners.controllers.dwa' in sys.modules, registry._PLUGINS_DONE)\n")
    paths = {"without": [str(ROOT / "src")],
             "with": [str(ROOT / "src"), str(PLUGIN / "src"), str(site)]}
    out = {k: subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             env={**os.environ, "PYTHONPATH": os.pathsep.join(v)},
                             check=True).stdout.strip() for k, v in paths.items()}
    assert out == {"without": "False []", "with": "True ['', 'bfs4']"}


def test_a_broken_plugin_is_named(tmp_path, fresh_plugins):
    site = _site(tmp_path, "[pathfuse.planners]\nbroken = no_such_module_xyz:register\n",
                 name="broken_plugin")
    fresh_plugins.syspath_prepend(str(site))
    with pytest.raises(registry.PluginError, match=r"^plug-in 'broken' \(no_such_module_xyz:"
                                                   r"register, from broken_plugin\): "
                                                   r"ModuleNotFoundError"):
        registry.load_plugins()
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), str(site)])}
    p = subprocess.run([sys.executable, "-m", "pathfuse.cli", "planners"], env=env,
                       capture_output=True, text=True)
    assert p.returncode != 0 and p.stdout == ""
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "plug-in 'broken'" in lines[0], p.stderr


def test_a_plugin_that_returns_garbage_is_named(fresh_plugins):
    pathfuse.register_global_planner("garbage", lambda pb: [[1.0, 2.0, 3.0]], "bad")
    with pytest.raises(registry.PluginError, match=r"^global planner 'garbage': must return "
                                                   r"\(N, 2\) finite waypoints"):
        plan(ROOM, START, GOAL, global_planner="garbage")
    pathfuse.register_global_planner("raises", lambda pb: 1 / 0, "bad")
    with pytest.raises(registry.PluginError, match="'raises': ZeroDivisionError"):
        plan(ROOM, START, GOAL, planner="fusion", global_planner="raises")


def test_no_path_from_a_plugin_is_a_status(fresh_plugins):
    pathfuse.register_global_planner("never", lambda pb: None, "finds nothing")
    for planner in ("astar", "fusion", "dwa"):
        r = plan(ROOM, START, GOAL, planner=planner, global_planner="never")
        assert r.status is Status.NO_PATH and "'never'" in r.message


def test_unknown_global_planner_names_the_choices():
    with pytest.raises(ConfigError, match=r"^fusion\.global_planner: must be one of astar, "
                                          r"jps, .*got 'nope'"):
        plan(ROOM, START, GOAL, planner="fusion", global_planner="nope")
    with pytest.raises(ConfigError, match=r"^apf\.global_planner: unknown parameter"):
        plan(ROOM, START, GOAL, planner="apf", global_planner="jps")


@pytest.mark.parametrize("name", ["astar", "jps", "astar-smooth", "thetastar",
                                  "lazy-thetastar", "shortest"])
def test_every_builtin_global_planner_is_registered_alike(name):
    gs = registry.get_global_planner(name)
    assert gs.plugin is None and gs.warmup is not None and gs.kernels is not None
    pb = Problem.create(ROOM, START, GOAL, 0.1)
    gp = run_global(name, pb)
    assert gp.success and gp.planner == name
    assert np.array_equal(gp.waypoints[0], START) and np.array_equal(gp.waypoints[-1], GOAL)


def test_preset_equals_follower_with_its_global_planner():
    """A preset is (global planner, controller, parameters): ``thetastar`` is the follower
    on the Theta* path, so ``astar`` told to follow Theta* plans the same path."""
    for name in ("thetastar", "jps", "shortest"):
        a = plan(ROOM, START, GOAL, planner=name, robot_radius_m=0.1)
        b = plan(ROOM, START, GOAL, planner="astar", global_planner=name, robot_radius_m=0.1)
        assert np.array_equal(a.path, b.path) and a.length == b.length


def test_an_experiment_combines_global_planners_with_a_controller(tmp_path):
    from pathfuse.bench.experiment import parse_experiment
    from pathfuse.planners.controllers.fusion import FusionParams

    text = """
name: gp
seeds: 1
maps:
  - name: tiny
    map: {rows: ["......", ".##...", "......", "...#.."]}
    start: [0.5, 0.5]
    goal: [5.5, 3.5]
planners:
  - fusion
  - name: fusion
    params: {global_planner: [jps, thetastar]}
  - name: dwa
    params: {global_planner: shortest}
"""
    runs = parse_experiment(text, tmp_path / "gp.yaml").expand()
    assert [r.full_params.get("global_planner") for r in runs] == \
        [None, "jps", "thetastar", "shortest"]
    # a run on the preset's own global planner hashes what it hashed before the parameter
    # existed, so the runs a study stored then are found again
    old = {k: v for k, v in dataclasses.asdict(FusionParams()).items()
           if k != "global_planner"}
    assert runs[0].full_params == json.loads(json.dumps(old))
    assert len({r.key for r in runs}) == 4
    with pytest.raises(ConfigError, match=r"planners\[1\]\.params\.global_planner\[1\]: "
                                          r"must be one of astar, jps, .*got 'nope'$"):
        parse_experiment(text.replace("[jps, thetastar]", "[jps, nope]"), tmp_path / "x.yaml")
