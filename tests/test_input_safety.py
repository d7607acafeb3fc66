"""Nothing a user types can crash, hang or exhaust pathfuse: the library side (issue 9).

Every case ends in a :class:`pathfuse.PathfuseError` whose one-line message names the
key or value (and, for a limit, the limit and how to raise it), or in a correct result.
The CLI side, under a memory limit, is in ``test_cli_input.py``.
"""

from __future__ import annotations

import math
import os
import time
from pathlib import Path

import numpy as np
import pytest

import pathfuse
from pathfuse.bench.keys import parse_seeds
from pathfuse.bench.parse import load_experiment, parse_experiment
from pathfuse.generate import random_map
from pathfuse.grid import GridMap
from pathfuse.io import load_map, read_movingai, read_ros_map, write_movingai
from pathfuse.io.inline import read_rows_yaml
from pathfuse.limits import DEFAULTS, LimitError, limit
from pathfuse.problem import Problem
from pathfuse.result import ConfigError, MapError, MapFormatError, PathfuseError
from pathfuse.safeyaml import load_yaml
from pathfuse.world import load_scenario

DATA = Path(__file__).parent / "data"
SANDBOX = DATA / "ros" / "nav2_tb3_sandbox"


def bomb(levels: int = 9, width: int = 10) -> str:
    """A "billion laughs" document: ``width ** levels`` strings once its aliases expand."""
    lines = [f"l0: &l0 [{', '.join(['lol'] * width)}]"]
    for i in range(1, levels):
        lines.append(f"l{i}: &l{i} [{', '.join([f'*l{i - 1}'] * width)}]")
    return "\n".join(lines) + "\n"


def nested(depth: int) -> str:
    return "[" * depth + "]" * depth


def one_line(exc: BaseException, *fragments: str, longest: int = 400) -> str:
    msg = str(exc)
    assert "\n" not in msg, msg
    assert len(msg) <= longest, msg          # a value is never printed in full
    for f in fragments:
        assert f in msg, msg
    return msg


# ------------------------------------------------------------------------------------ YAML
def test_alias_bomb_refused_before_expanding():
    t0 = time.process_time()
    with pytest.raises(LimitError) as ei:
        load_yaml(bomb(), "lol.yaml")
    assert time.process_time() - t0 < 5
    one_line(ei.value, "lol.yaml", "aliases expanded", "MAX_YAML_NODES",
             "PATHFUSE_MAX_YAML_NODES")


def test_small_aliases_still_work():
    doc = load_yaml("base: &b {r1_m: 1.0, r2_m: 2.0}\nother: *b\nmerged: {<<: *b, r1_m: 3}\n",
                    "x.yaml")
    assert doc["other"] == {"r1_m": 1.0, "r2_m": 2.0}
    assert doc["merged"] == {"r1_m": 3, "r2_m": 2.0}


@pytest.mark.parametrize("depth", [5_000, 20_000])
def test_deep_nesting_is_a_clean_error(depth):
    with pytest.raises(LimitError) as ei:
        load_yaml("a: " + nested(depth), "deep.yaml")
    one_line(ei.value, "deep.yaml", "line 1", "nested deeper than 100 levels", "MAX_YAML_DEPTH")


@pytest.mark.parametrize("text, fragment", [
    ("? [1, 2]\n: 3\n", "a mapping key must be text or a number, got a list"),
    ("? {a: 1}\n: 3\n", "a mapping key must be text or a number, got a mapping"),
    ("a: 1\nb: 2\na: 3\n", "line 3, column 1: invalid YAML: duplicate key 'a'"),
    ("a: !!python/object/apply:os.system [ls]\n", "could not determine a constructor"),
    ("a: [1, 2\n", "invalid YAML"),
])
def test_malformed_yaml(text, fragment):
    with pytest.raises(ConfigError) as ei:
        load_yaml(text, "bad.yaml")
    one_line(ei.value, "bad.yaml", fragment)


@pytest.mark.parametrize("text, value", [
    ("1e-2", 0.01), ("5E3", 5000.0), ("-1.5e+3", -1500.0), (".5e-1", 0.05), ("1.0", 1.0),
    ("1e", "1e"), ("10", 10), ("0.1", 0.1), ("1_000.5", 1000.5), ("-.inf", -math.inf),
])
def test_floats_as_users_write_them(text, value):
    assert load_yaml(f"v: {text}", "x.yaml")["v"] == value


def _write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


def _ros_yaml(extra: str) -> str:
    return (f"image: {SANDBOX / 'tb3_sandbox.pgm'}\nresolution: 0.05\norigin: [0, 0, 0]\n"
            f"negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n{extra}")


_SCENARIO = "map: {rows: ['......', '......', '......']}\nstart: [0.5, 1.5]\ngoal: [5.5, 1.5]\n"
_EXPERIMENT = "maps: [{name: p, map: paper}]\nplanners: [astar]\n"


def _readers(tmp_path):
    """Every YAML reader: (name, function of the document's extra text)."""
    def ros(extra):
        return read_ros_map(_write(tmp_path, "m.yaml", _ros_yaml(extra)))

    def ros_via_load_map(extra):
        return load_map(_write(tmp_path, "m2.yaml", _ros_yaml(extra)))

    def rows(extra):
        return read_rows_yaml(_write(tmp_path, "r.yaml", "rows: ['...', '...']\n" + extra))

    def scenario(extra):
        return load_scenario(_write(tmp_path, "s.yaml", _SCENARIO + extra))

    def experiment(extra):
        return load_experiment(_write(tmp_path, "e.yaml", _EXPERIMENT + extra))

    return {"ros": ros, "ros-load_map": ros_via_load_map, "rows": rows, "scenario": scenario,
            "experiment": experiment}


@pytest.mark.parametrize("reader", ["ros", "ros-load_map", "rows", "scenario", "experiment"])
def test_every_yaml_reader_refuses_an_alias_bomb(tmp_path, reader):
    f = _readers(tmp_path)[reader]
    key = {"ros": "comment", "ros-load_map": "comment", "rows": "name",
           "scenario": "description", "experiment": "name"}[reader]
    t0 = time.process_time()
    with pytest.raises(LimitError) as ei:
        f(bomb() + f"{key}: *l8\n")
    assert time.process_time() - t0 < 5
    one_line(ei.value, "MAX_YAML_NODES")


@pytest.mark.parametrize("reader", ["ros", "ros-load_map", "rows", "scenario", "experiment"])
def test_every_yaml_reader_refuses_deep_nesting(tmp_path, reader):
    with pytest.raises(LimitError) as ei:
        _readers(tmp_path)[reader]("deep: " + nested(20_000) + "\n")
    one_line(ei.value, "nested deeper than", "MAX_YAML_DEPTH")


@pytest.mark.parametrize("reader", ["ros", "rows", "scenario", "experiment"])
def test_every_yaml_reader_refuses_a_list_key(tmp_path, reader):
    with pytest.raises(PathfuseError) as ei:
        _readers(tmp_path)[reader]("? [1, 2]\n: 3\n")
    one_line(ei.value, "a mapping key must be text or a number")


@pytest.mark.parametrize("reader", ["rows", "scenario", "experiment"])
def test_every_yaml_reader_shows_a_shortened_value(tmp_path, reader):
    # a small alias expansion is allowed; the message shows only the start of the value
    doc = "big: &big [" + ", ".join(["xxxxxxxxxx"] * 2000) + "]\n"
    key = {"rows": "name", "scenario": "description", "experiment": "name"}[reader]
    with pytest.raises(PathfuseError) as ei:
        _readers(tmp_path)[reader](doc + f"{key}: *big\n")
    one_line(ei.value)


@pytest.mark.parametrize("doc", [
    "start: *big\n", "obstacles: [{position: *big, velocity: [0, 0], radius: 0.2}]\n"])
def test_scenario_values_shortened(tmp_path, doc):
    base = "big: &big [" + ", ".join(["1"] * 5000) + "]\n"
    text = base + "map: {rows: ['......', '......', '......']}\ngoal: [5.5, 1.5]\n"
    if not doc.startswith("start"):
        text += "start: [0.5, 1.5]\n"
    with pytest.raises(PathfuseError) as ei:
        load_scenario(_write(tmp_path, "s.yaml", text + doc))
    one_line(ei.value)


def test_yaml_file_size_is_capped(tmp_path, monkeypatch):
    monkeypatch.setenv("PATHFUSE_MAX_YAML_BYTES", "1000")
    p = _write(tmp_path, "s.yaml", _SCENARIO + "description: " + "x" * 2000 + "\n")
    with pytest.raises(LimitError) as ei:
        load_scenario(p)
    one_line(ei.value, "s.yaml", "1000 bytes", "PATHFUSE_MAX_YAML_BYTES")


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
@pytest.mark.parametrize("name", ["zero.yaml", "zero.map"])
def test_a_link_to_dev_zero_is_refused(tmp_path, name):
    p = tmp_path / name
    p.symlink_to("/dev/zero")
    with pytest.raises(LimitError) as ei:
        load_map(p)
    one_line(ei.value, name, "is a device, not a file")


def test_rows_as_one_string_is_refused():
    with pytest.raises(MapFormatError) as ei:
        read_rows_yaml({"rows": "...."})
    one_line(ei.value, "'rows' must be a list of strings", "'....'")
    # a multi-line block is still a map
    assert read_rows_yaml({"rows": "..\n#.\n"}).shape == (2, 2)


def test_floats_in_experiment_and_scenario_files(tmp_path):
    exp = parse_experiment("maps: [{name: p, map: paper}]\nplanners:\n  - name: apf\n"
                           "    params: {step_m: 1e-2, k_att: 4E1}\n", tmp_path / "e.yaml")
    assert exp.planners[0].params == (("step_m", (0.01,)), ("k_att", (40.0,)))
    sc = load_scenario(_write(tmp_path, "s.yaml", _SCENARIO + "dt: 5e-2\n"))
    assert sc.dt == 0.05


# ------------------------------------------------------------------------------------ limits
def test_limits_are_named_and_overridable(monkeypatch):
    assert set(DEFAULTS) == {"MAX_CELLS", "MAX_RUNS", "MAX_TICKS", "MAX_STEPS",
                             "MAX_FILE_BYTES", "MAX_YAML_BYTES", "MAX_YAML_NODES",
                             "MAX_YAML_DEPTH"}
    monkeypatch.setenv("PATHFUSE_MAX_CELLS", "123")
    assert limit("MAX_CELLS") == 123
    monkeypatch.setenv("PATHFUSE_MAX_CELLS", "lots")
    with pytest.raises(ConfigError, match="PATHFUSE_MAX_CELLS: must be an integer >= 1"):
        limit("MAX_CELLS")


@pytest.mark.parametrize("value, fragment", [
    (10**9, "a seed count: 1000000000 is above the limit of 2000000 (MAX_RUNS"),
    (2**64, "a seed count: 18446744073709551616 is above the limit"),
    ("0:1000000000", "a seed count: 1000000000 is above the limit"),
    ({"start": 0, "count": 10**12}, "is above the limit"),
    ([10**23], "seeds[0]: a seed must be an integer in [0, 2**63), got 100000000000000000000000"),
    ("5:3", "'5:3' holds no seed"),
    (f"{2**63 - 1}:{2**63 + 1}", "seeds must be integers in [0, 2**63)"),
])
def test_seed_limits(value, fragment):
    t0 = time.process_time()
    with pytest.raises(ConfigError) as ei:
        parse_seeds(value)
    assert time.process_time() - t0 < 1
    one_line(ei.value, fragment)


def test_largest_seed_is_accepted():
    assert parse_seeds([2**63 - 1]) == (2**63 - 1,)


def test_parameter_grid_limit(tmp_path):
    axis = lambda n, scale: "[" + ", ".join(str(scale * (i + 1)) for i in range(n)) + "]"  # noqa: E731
    text = ("maps: [{name: p, map: paper}]\nplanners:\n  - name: fusion\n    params:\n"
            f"      r1_m: {axis(1000, 0.01)}\n      r2_m: {axis(1000, 0.01)}\n"
            f"      step_m: {axis(100, 0.001)}\n")
    t0 = time.process_time()
    with pytest.raises(LimitError) as ei:
        parse_experiment(text, tmp_path / "grid.yaml")
    assert time.process_time() - t0 < 30
    one_line(ei.value, "grid.yaml", "planners[0].params: the parameter grid (1000 x 1000 x 100)",
             "100000000 is above the limit of 2000000", "PATHFUSE_MAX_RUNS")


def test_run_list_limit_counted_before_building(tmp_path, monkeypatch):
    monkeypatch.setenv("PATHFUSE_MAX_RUNS", "50")
    exp = parse_experiment("seeds: 30\nmaps: [{name: p, map: paper}]\nplanners: [astar, apf]\n",
                           tmp_path / "e.yaml")
    with pytest.raises(LimitError) as ei:
        exp.expand()
    one_line(ei.value, "e.yaml: the experiment's runs: 60 is above the limit of 50")
    with pytest.raises(LimitError):
        parse_experiment("maps: [{name: p, map: paper, queries: {random: 100000}}]\n"
                         "planners: [astar]\n", tmp_path / "q.yaml")


def test_movingai_header_checked_before_allocating(tmp_path):
    p = tmp_path / "wide.map"
    p.write_text("type octile\nheight 3\nwidth 1000000000\nmap\n...\n...\n...\n")
    with pytest.raises(LimitError) as ei:
        read_movingai(p)
    one_line(ei.value, "wide.map", "3 x 1000000000 = 3000000000 cells", "MAX_CELLS")


def test_images_and_arrays_checked_before_decoding(tmp_path, monkeypatch):
    from PIL import Image

    Image.fromarray(np.full((20, 30), 255, np.uint8)).save(tmp_path / "a.png")
    np.save(tmp_path / "a.npy", np.zeros((20, 30), bool))
    monkeypatch.setenv("PATHFUSE_MAX_CELLS", "100")
    for name in ("a.png", "a.npy"):
        with pytest.raises(LimitError) as ei:
            load_map(tmp_path / name, resolution=0.1)
        one_line(ei.value, name, "20 x 30 = 600 cells", "limit of 100 cells")


def test_random_map_of_1e14_cells():
    with pytest.raises(LimitError) as ei:
        random_map(size_m=(1e7, 1e7), resolution=1.0, obstacles=0)
    one_line(ei.value, "random map", "10000000 x 10000000", "MAX_CELLS")
    with pytest.raises(MapError):
        random_map(size_m=1e300, resolution=1e-300, obstacles=0)


def test_inflation_by_a_huge_radius():
    g = GridMap.from_rows(["..#.", "....", "...."])
    t0 = time.process_time()
    assert g.inflate(1e9).occupied.all()
    assert g.cspace(1e5).occupied.all()
    assert time.process_time() - t0 < 1
    res = pathfuse.plan(g, (0.5, 0.5), (3.5, 0.5), robot_radius_m=1e5)
    assert res.status is pathfuse.Status.START_OCCUPIED
    assert "overlaps the map's edge" in res.message


@pytest.mark.parametrize("seed", range(6))
def test_wide_inflation_matches_the_kernel(seed, monkeypatch):
    """Radii above the dilation kernel's width use the distance transform: same cells."""
    import pathfuse.grid as gridmod

    rng = np.random.default_rng(seed)
    occ = rng.random((int(rng.integers(5, 60)), int(rng.integers(5, 60)))) < 0.03
    res = float(rng.choice([1.0, 0.05, 0.3]))
    for r in [res * k / 4 for k in range(1, 120, 7)] + list(rng.random(5) * 40 * res):
        monkeypatch.setattr(gridmod, "_KERNEL_MAX", 10**9)
        a = GridMap(occ, res)._inflate(r).occupied
        monkeypatch.setattr(gridmod, "_KERNEL_MAX", 0)
        b = GridMap(occ, res)._inflate(r).occupied
        assert np.array_equal(a, b), (seed, r)


@pytest.mark.parametrize("extra, fragment", [
    ("time_limit: 1e6\n", "1e+06 s / 0.1 s = 1e+07 ticks"),
    ("dt: 1e-9\n", "60 s / 1e-09 s = 6e+10 ticks"),
])
def test_episode_tick_limit(tmp_path, extra, fragment):
    with pytest.raises(LimitError) as ei:
        load_scenario(_write(tmp_path, "s.yaml", _SCENARIO + extra))
    one_line(ei.value, "s.yaml", "time_limit / dt", fragment, "MAX_TICKS")


def test_long_stall_time_is_fine():
    sc = load_scenario({"map": {"rows": ["......"] * 3}, "start": [0.5, 1.5],
                        "goal": [5.5, 1.5], "stall_time": 1e300, "dt": 1e-3})
    assert pathfuse.simulate(sc, planner="astar").status is pathfuse.Status.SUCCESS


# ------------------------------------------------------------- library calls (issue item 7)
EMPTY = GridMap.from_rows(["......"] * 3)


def test_tiny_step_is_refused_with_the_limit():
    with pytest.raises(LimitError) as ei:
        pathfuse.plan(EMPTY, (0.5, 1.5), (5.5, 1.5), "apf", step_m=1e-300)
    one_line(ei.value, "step_m", "1e-300", "MAX_STEPS", "PATHFUSE_MAX_STEPS")


@pytest.mark.parametrize("planner", ["astar", "apf", "fusion", "ref6", "ref7", "astar-replan"])
def test_huge_budget_works(planner):
    res = pathfuse.plan(EMPTY, (0.5, 1.5), (5.5, 1.5), planner,
                        budget=pathfuse.Budget(max_iterations=10**30))
    assert res.status is pathfuse.Status.SUCCESS, res.message


def test_budget_of_the_wrong_kind():
    with pytest.raises(ConfigError) as ei:
        pathfuse.plan(EMPTY, (0.5, 1.5), (5.5, 1.5), budget="x")
    one_line(ei.value, "budget: must be a pathfuse.Budget, got str")


@pytest.mark.parametrize("rows, fragment", [
    ([1, 2], "rows[0] must be a string, got 1"),
    ("....", "rows must be a list of strings, got '....'"),
    ([], "at least one row"),
])
def test_from_rows_of_the_wrong_kind(rows, fragment):
    with pytest.raises(MapError) as ei:
        GridMap.from_rows(rows)
    one_line(ei.value, fragment)


def test_write_movingai_to_an_unwritable_place(tmp_path):
    with pytest.raises(MapFormatError) as ei:
        write_movingai(EMPTY, "/proc/x.map")
    one_line(ei.value, "/proc/x.map: cannot write the map file")
    with pytest.raises(MapFormatError):
        write_movingai(EMPTY, tmp_path / "missing" / "x.map")


def test_ros_resolution_1e308(tmp_path):
    p = _write(tmp_path, "m.yaml", _ros_yaml("").replace("resolution: 0.05",
                                                             "resolution: 1e308"))
    with pytest.raises(MapError) as ei:
        read_ros_map(p)
    one_line(ei.value, "m.yaml", "1e+12 m", "MAX_EXTENT_M")


def test_map_extent_checked():
    with pytest.raises(MapError, match="reaches 1e\\+13 m"):
        GridMap(np.zeros((10, 10), bool), resolution=1e12)
    GridMap(np.zeros((10, 10), bool), resolution=1e10)   # 1e11 m: fine


def test_disc_on_unknown_cells_says_unknown():
    occ = np.zeros((5, 5), bool)
    unknown = np.zeros((5, 5), bool)
    occ[2, 3] = unknown[2, 3] = True
    g = GridMap(occ, meta={"unknown": unknown})
    failure = Problem.create(g, (1.0, 1.0), (2.5, 2.5), robot_radius_m=0.6).failure()
    assert failure is not None and failure[0] is pathfuse.Status.GOAL_OCCUPIED
    assert "overlaps an unknown cell" in failure[1]
    failure = Problem.create(g, (0.5, 0.5), (3.5, 2.5)).failure()
    assert "lies in an unknown cell" in failure[1]


def test_empty_scen_is_an_error(tmp_path):
    from pathfuse.io import read_scen

    p = _write(tmp_path, "e.scen", "version 1\n")
    with pytest.raises(MapFormatError, match="holds no problem line"):
        read_scen(p, read_movingai(DATA / "movingai" / "den312d.map"))


# ------------------------------------------- the memory-hungry calls, under a memory limit
_HUNGRY = {
    "inflate": "from pathfuse.grid import GridMap\n"
               "assert GridMap.from_rows(['..#.', '....', '....']).inflate(1e9).occupied.all()",
    "cspace": "import pathfuse\nfrom pathfuse.grid import GridMap\n"
              "g = GridMap.from_rows(['....'] * 3)\n"
              "print(pathfuse.plan(g, (0.5, 0.5), (3.5, 0.5), robot_radius_m=1e5).status.name)",
    "random_map": "from pathfuse.generate import random_map\n"
                  "random_map(size_m=1e7, resolution=1.0, obstacles=1)",
    "seeds": "from pathfuse.bench.keys import parse_seeds\nparse_seeds('0:1000000000')",
    "bomb": f"from pathfuse.safeyaml import load_yaml\nload_yaml({bomb()!r}, 'b.yaml')",
    "huge_budget": "import pathfuse\nfrom pathfuse.grid import GridMap\n"
                   "g = GridMap.from_rows(['......'] * 3)\n"
                   "b = pathfuse.Budget(max_iterations=10**30)\n"
                   "print(pathfuse.plan(g, (0.5, 1.5), (5.5, 1.5), 'apf', budget=b).status.name)",
}


@pytest.mark.parametrize("case", sorted(_HUNGRY))
def test_hungry_calls_stay_within_a_memory_limit(case):
    """Each call runs in a child limited to 2 GB of address space (the unchecked versions
    took 4-17 GB) and 60 s: it must end in a pathfuse error or a result, never MemoryError."""
    import resource
    import subprocess
    import sys

    def limit_memory():  # pragma: no cover - runs in the child
        resource.setrlimit(resource.RLIMIT_AS, (2 * 1024**3, 2 * 1024**3))

    code = ("import sys\nfrom pathfuse import PathfuseError\ntry:\n"
            + "".join("    " + ln + "\n" for ln in _HUNGRY[case].splitlines())
            + "except PathfuseError as exc:\n    print('error:', exc)\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=60, preexec_fn=limit_memory)
    assert p.returncode == 0, p.stderr
    assert "Traceback" not in p.stderr
    expected = {"inflate": "", "cspace": "START_OCCUPIED", "random_map": "error: random map",
                "seeds": "error: seeds: a seed count", "bomb": "error: b.yaml",
                "huge_budget": "SUCCESS"}[case]
    assert expected in p.stdout, p.stdout
