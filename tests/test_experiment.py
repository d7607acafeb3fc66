"""Experiment files: validation with one-line errors naming the key, deterministic run lists."""

from __future__ import annotations

import hashlib
import json
import shutil
from dataclasses import dataclass
from pathlib import Path

import pytest

from pathfuse.bench.experiment import canonical_json, load_experiment, parse_experiment
from pathfuse.planners.registry import register_function
from pathfuse.result import ConfigError, PlanResult, Status


@dataclass(frozen=True)
class _Params:
    k_att: float = 40.0
    k_rep: float = 5.0
    r1_m: float = 1.5
    r2_m: float = 2.0
    mode: str = "a"

    def __post_init__(self):
        for k in ("k_att", "r1_m", "r2_m"):
            if getattr(self, k) <= 0:
                raise ConfigError(f"{k} must be > 0, got {getattr(self, k)}")


def _never(grid, start, goal, params, budget):  # experiments are only expanded here
    return PlanResult(Status.NO_PATH)


# two planners of our own, so that these tests do not depend on the real ones
# (registered for each test; conftest.py restores the registry afterwards)
@pytest.fixture(autouse=True)
def _test_planners():
    register_function("xsweep", _never, _Params, "test planner for experiment parsing")
    register_function("xother", _never, _Params, "second test planner")

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared" / "data" / "movingai"
MOVINGAI = REPO / "tests" / "data" / "movingai"  # the repository's copies of small maps

ROWS = '{rows: ["......", ".##...", "......", "...#.."]}'


def write(tmp_path: Path, text: str, name: str = "exp.yaml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def basic(extra: str = "", planners: str = "  - xsweep\n") -> str:
    return f"""
name: t
seeds: 3
{extra}
maps:
  - name: tiny
    map: {ROWS}
    start: [0.5, 0.5]
    goal: [5.5, 3.5]
planners:
{planners}"""


# --------------------------------------------------------------------------- expansion
def test_grid_is_cartesian_product_in_file_order(tmp_path):
    exp = load_experiment(write(tmp_path, basic(planners="""
  - xsweep
  - name: xother
    params: {r1_m: [0.5, 1, 1.5, 2], r2_m: [1, 3], k_att: 40}
""")))
    runs = exp.expand()
    assert len(runs) == 3 * (1 + 4 * 2)
    # order: seed > planner > combination, first key outermost
    first_seed = [r for r in runs if r.seed == 0]
    assert [r.planner for r in first_seed] == ["xsweep"] + ["xother"] * 8
    combos = [(r.params["r1_m"], r.params["r2_m"]) for r in first_seed[1:]]
    assert combos == [(a, b) for a in (0.5, 1.0, 1.5, 2.0) for b in (1.0, 3.0)]
    # YAML ints become floats for float parameters, so 1 and 1.0 are the same run
    assert all(isinstance(r.params["r1_m"], float) for r in first_seed[1:])
    assert [r.seed for r in runs[::9]] == [0, 1, 2]
    # config names say the swept values, not the fixed ones
    assert first_seed[1].config == "xother(r1_m=0.5,r2_m=1)"
    assert first_seed[0].config == "xsweep"
    assert len({r.key for r in runs}) == len(runs)


def test_run_key_is_sha256_of_canonical_payload(tmp_path):
    runs = load_experiment(write(tmp_path, basic())).expand()
    for r in runs:
        payload = json.loads(r.payload)
        again = json.dumps(payload, sort_keys=True, separators=(",", ":"))
        assert hashlib.sha256(again.encode()).hexdigest() == r.key
        # the payload holds the full parameters, defaults included
        assert payload["params"]["k_att"] == 40.0 and payload["seed"] == r.seed
        assert payload["planner"] == "xsweep" and payload["query"]["start"] == [0.5, 0.5]


def test_expansion_is_deterministic_and_key_order_free(tmp_path):
    a = load_experiment(write(tmp_path, basic(planners="""
  - name: xother
    params: {r1_m: [1, 2], r2_m: 3}
"""), "a.yaml")).expand()
    b = load_experiment(write(tmp_path, basic(planners="""
  - params: {r2_m: 3.0, r1_m: [1.0, 2.0]}
    name: xother
"""), "b.yaml")).expand()
    assert [r.key for r in a] == [r.key for r in b]
    assert [r.key for r in a] == [r.key for r in load_experiment(tmp_path / "a.yaml").expand()]


def test_key_changes_with_any_parameter(tmp_path):
    base = {r.key for r in load_experiment(write(tmp_path, basic(), "a.yaml")).expand()}
    changed = [
        basic(planners="  - name: xsweep\n    params: {k_rep: 6}\n"),
        basic(extra="limits: {time_limit_s: 2}"),
        basic(extra="robot_radius_m: 0.1"),
        basic().replace("goal: [5.5, 3.5]", "goal: [5.5, 2.5]"),
    ]
    for i, text in enumerate(changed):
        keys = {r.key for r in load_experiment(write(tmp_path, text, f"c{i}.yaml")).expand()}
        assert not keys & base, text


def test_seed_override_and_forms(tmp_path):
    p = write(tmp_path, basic())
    assert [r.seed for r in load_experiment(p, seeds="5:8").expand()] == [5, 6, 7]
    assert [r.seed for r in load_experiment(p, seeds=[9, 2]).expand()] == [9, 2]
    assert [r.seed for r in load_experiment(p, seeds=2).expand()] == [0, 1]
    # the same seed gives the same key whatever the seed list
    k3 = {r.seed: r.key for r in load_experiment(p).expand()}
    k7 = {r.seed: r.key for r in load_experiment(p, seeds="1:3").expand()}
    assert k7 == {1: k3[1], 2: k3[2]}


def test_paper_map_gets_seed_per_run_and_default_query(tmp_path):
    exp = load_experiment(write(tmp_path, "seeds: 3\nmaps: [paper]\nplanners: [xsweep]\n"))
    runs = exp.expand()
    specs = [r.map_spec for r in runs]
    assert specs == [{"paper": {"seed": s}} for s in range(3)]
    assert len({r.map_key for r in runs}) == 3
    assert runs[0].query == {"start": [1.0, 1.0], "goal": [11.0, 11.0]}
    # an explicit seed fixes the map for every run seed
    fixed = load_experiment(write(tmp_path, "seeds: 3\nmaps: [{map: {paper: 7}}]\n"
                                  "planners: [xsweep]\n", "f.yaml")).expand()
    assert {r.map_key for r in fixed} == {fixed[0].map_key}
    assert fixed[0].map_spec == {"paper": {"seed": 7}}


@pytest.mark.skipif(not (MOVINGAI / "den312d.map").is_file(), reason="test data missing")
def test_scen_lines_selection_and_portable_keys(tmp_path):
    for f in ("den312d.map", "den312d.map.scen"):
        (tmp_path / "data").mkdir(exist_ok=True)
        shutil.copy(MOVINGAI / f, tmp_path / "data" / f)
    text = """
seeds: [0]
maps:
  - name: den
    map: {movingai: data/den312d.map}
    scen: data/den312d.map.scen
    lines: %s
planners: [xsweep]
"""
    runs = load_experiment(write(tmp_path, text % "[2, 10, 5]")).expand()
    assert [r.query["line"] for r in runs] == [2, 10, 5]
    lines = (MOVINGAI / "den312d.map.scen").read_text().splitlines()
    cols = lines[9].split("\t")  # file line 10
    assert runs[1].query["optimal_length"] == pytest.approx(float(cols[8]))
    assert runs[1].query["start"] == [int(cols[4]) + 0.5, 81 - int(cols[5]) - 0.5]
    first = load_experiment(write(tmp_path, text % "4")).expand()
    assert [r.query["line"] for r in first] == [2, 3, 4, 5]
    every = load_experiment(write(tmp_path, text % "{every: 100}")).expand()
    assert [r.query["line"] for r in every] == [2, 102, 202]
    s1 = [r.query["line"] for r in load_experiment(
        write(tmp_path, text % "{sample: 7, seed: 3}")).expand()]
    s2 = [r.query["line"] for r in load_experiment(
        write(tmp_path, text % "{sample: 7, seed: 3}")).expand()]
    assert s1 == s2 and s1 == sorted(s1) and len(set(s1)) == 7
    # moving the study (experiment + data) elsewhere keeps every key
    keys = [r.key for r in load_experiment(write(tmp_path, text % "4")).expand()]
    moved = tmp_path / "elsewhere"
    shutil.copytree(tmp_path / "data", moved / "data")
    assert keys == [r.key for r in load_experiment(write(moved, text % "4")).expand()]
    # ... but editing the map file changes them
    (moved / "data" / "den312d.map").write_text(
        (MOVINGAI / "den312d.map").read_text().replace("@", ".", 1))
    assert not set(keys) & {r.key for r in load_experiment(moved / "exp.yaml").expand()}


def test_random_queries_and_dynamic_entries(tmp_path):
    (tmp_path / "sc.yaml").write_text('map: {rows: ["......"]}\nstart: [0.5, 0.5]\n'
                                      'goal: [5.5, 0.5]\nrobot: {radius: 0.2}\n')
    (tmp_path / "bad.yaml").write_text("anything: 1\n")
    text = """
seeds: 2
maps:
  - name: r
    map: {random: {size: [20, 20], density: 0.1}}
    queries: {random: 3, min_distance_m: 5}
  - name: dyn
    dynamic: sc.yaml
planners: %s
"""
    # xsweep is an offline-only plug-in function: it cannot drive a dynamic entry
    with pytest.raises(ConfigError, match=r"maps\[1\]: no planner of this experiment runs "
                                          r"dynamic maps \(planners that run online: astar, "):
        load_experiment(write(tmp_path, text % "[xsweep]"))
    with pytest.raises(ConfigError, match=r"planners\[1\].name: unknown planner 'nope' "
                                          r"\(choose from static: .*; dynamic: "):
        load_experiment(write(tmp_path, text % "[xsweep, nope]"))
    with pytest.raises(ConfigError, match=r"maps\[1\].dynamic: .*bad.yaml: anything: unknown"):
        load_experiment(write(tmp_path, text.replace("sc.yaml", "bad.yaml")
                              % "[xsweep, {name: fusion, kinds: [dynamic]}]"))
    gen = "  - name: gen\n    dynamic: {generate: {moving: 2, bogus: 1}}\n"
    with pytest.raises(ConfigError, match=r"maps\[2\].dynamic.generate.bogus: unknown argument"):
        load_experiment(write(tmp_path, text.replace("planners:", gen + "planners:")
                              % "[xsweep, {name: fusion, kinds: [dynamic]}]"))
    exp = load_experiment(write(tmp_path, text % "[xsweep, {name: fusion, kinds: [dynamic]}]"))
    assert [p.kinds for p in exp.planners] == [("static",), ("dynamic",)]
    runs = exp.expand()
    assert {r.planner for r in runs if r.kind == "static"} == {"xsweep"}
    static = [r for r in runs if r.kind == "static"]
    assert len(static) == 2 * 3
    assert [r.query["random"] for r in static] == [0, 1, 2, 0, 1, 2]
    assert static[0].map_spec == {"random": {"size": [20, 20], "density": 0.1, "seed": 0}}
    dyn = [r for r in runs if r.kind == "dynamic"]
    assert len(dyn) == 2 and dyn[0].reference is None
    assert dyn[0].map_spec["dynamic"] == str((tmp_path / "sc.yaml").resolve())


# --------------------------------------------------------------------------- errors
BAD = [
    ("planners:\n  - name: xother\n    params: {r1_m: [0.5, -1]}\nmaps: [paper]\n",
     "planners[0].params.r1_m[1]: "),
    ("planners:\n  - name: xother\n    params: {rr: 1}\nmaps: [paper]\n",
     "planners[0].params.rr: planner 'xother' has no such parameter"),
    ("planners: [xsweep, {name: nosuch}]\nmaps: [paper]\n", "planners[1].name: unknown planner"),
    ("planners: [xsweep]\nmaps: [paper]\nseeds: -3\n", "seeds: a seed count must be >= 1"),
    ("planners: [xsweep]\nmaps: [paper]\nseeds: [1, x]\n", "seeds[1]: "),
    ("planners: [xsweep]\nmaps: [paper]\nlimits: {time_limit_s: 0}\n", "limits.time_limit_s: "),
    ("planners: [xsweep]\nmaps: [paper]\nlimits: {max_iter: 5}\n",
     "limits.max_iter: unknown limit"),
    ("planners: [xsweep]\nmaps: [paper]\nbogus: 1\n", "bogus: unknown key"),
    ("planners: [xsweep]\nmaps: [{map: {movingai: nope.map}, start: [0, 0], goal: [1, 1]}]\n",
     "maps[0].map.movingai: no such file"),
    ("planners: [xsweep]\nmaps: [paper, {map: {rows: ['..']}}]\n",
     "maps[1]: needs start/goal, queries or scen"),
    ("planners: [xsweep]\nmaps: [{map: {rows: ['...']}, start: [0.5, 0.5], goal: [9, 0.5]}]\n",
     "maps[0].goal: (9, 0.5) lies outside map"),
    ("planners: [xsweep]\nmaps: [{map: {rows: ['..']}, start: [0.5], goal: [1, 0.5]}]\n",
     "maps[0].start: must be two numbers [x, y]"),
    ("planners: [xsweep]\nmaps: [paper, paper]\n", "maps[1].name: 'paper' is already the name"),
    ("planners: [xsweep]\nmaps: [{map: {random: {size: [5, 5], density: 2}}, "
     "queries: {random: 1}}]\n", "maps[0].map: "),
    ("planners: [xsweep, xsweep]\nmaps: [paper]\n", "planners[1] on maps[0] repeats the runs"),
    ("planners: [xsweep]\nmaps: [{map: paper, queries: {random: 0}}]\n",
     "maps[0].queries.random: must be an integer >= 1"),
    ("planners: [xsweep]\nmaps: [{map: {paper: 1, rows: ['.']}}]\n",
     "maps[0].map: name exactly one map family"),
    ("planners: [xsweep]\nmaps: [paper]\nreference: nosuch\n", "reference: unknown planner"),
    ("planners: [xsweep]\nmaps: [paper]\nimports: [missing.py]\n", "imports[0]: no such file"),
    ("planners: [xsweep]\nmaps: [{map: paper, lines: 3}]\n", "maps[0].lines: only used with scen"),
    ("planners: [xsweep]\nmaps: [paper\n", "invalid YAML"),
    ("- just a list\n", "must hold a mapping"),
]


@pytest.mark.parametrize("text,expected", BAD)
def test_bad_files_give_one_line_naming_the_key(tmp_path, text, expected):
    p = write(tmp_path, text)
    with pytest.raises(ConfigError) as ei:
        load_experiment(p).expand()
    msg = str(ei.value)
    assert "\n" not in msg
    assert msg.startswith(f"{p}: ")
    assert expected in msg, msg


def test_missing_file_and_yaml_line_number(tmp_path):
    with pytest.raises(ConfigError, match="no such experiment file"):
        load_experiment(tmp_path / "nope.yaml")
    with pytest.raises(ConfigError, match=r"x.yaml: line 2, column \d+: invalid YAML"):
        parse_experiment("a: 1\nb: c: d\n", tmp_path / "x.yaml")


def test_a_map_yaml_file_with_rows_runs_as_load_map_reads_it(tmp_path):
    """``map: FILE.yaml`` names a ROS map or an inline-rows map, as ``load_map`` reads it."""
    import numpy as np

    from pathfuse.bench.runner import run_experiment
    from pathfuse.bench.spec import load_map as load_spec
    from pathfuse.bench.store import ResultStore
    from pathfuse.io import load_map

    rows = tmp_path / "maps" / "corridor.yaml"
    rows.parent.mkdir()
    rows.write_text('rows:\n  - "......"\n  - ".##..."\n  - "......"\nresolution: 0.5\n'
                    "origin: [1, 2]\n")
    text = ("seeds: 1\nmaps:\n  - map: maps/corridor.yaml\n    start: [1.25, 2.25]\n"
            "    goal: [3.75, 3.25]\nplanners: [astar]\n")
    exp = load_experiment(write(tmp_path, text))
    (run,) = exp.expand()
    assert run.group == "corridor"  # the entry is named after the file, as other map files
    want, got = load_map(rows), load_spec(run.map_spec, exp.base_dir)
    assert np.array_equal(got.occupied, want.occupied) and got.name == want.name == "corridor"
    assert (got.resolution, tuple(got.origin)) == (want.resolution, tuple(want.origin))
    store = ResultStore(":memory:")
    try:
        summary = run_experiment(exp, store, workers=1, progress=False)
        stored = store.rows_by_key([run.key])[run.key]
    finally:
        store.close()
    assert summary.ran == 1 and stored["status_name"] == "SUCCESS"
    # the key follows the file's contents
    rows.write_text(rows.read_text().replace(".##...", ".#...."))
    assert load_experiment(tmp_path / "exp.yaml").expand()[0].key != run.key
    # a ROS map YAML is still a ROS map
    ros = REPO / "tests" / "data" / "ros" / "nav2_tb3_sandbox" / "tb3_sandbox.yaml"
    exp = load_experiment(write(tmp_path, f"maps:\n  - map: {ros}\n    start: [-1.0, -0.5]\n"
                                          "    goal: [1.5, 0.5]\nplanners: [xsweep]\n",
                                "ros.yaml"))
    assert exp.maps[0].family == "ros"


@pytest.mark.parametrize("content, expected", [
    ('rows:\n  - "..."\n  - ".."\n', "ragged rows"),
    ('rows: ["..."]\ncolour: red\n', "unknown key 'colour'"),
    ("size: 3\n", "needs an 'image' key (ROS map_server map) or a 'rows' key"),
])
def test_a_bad_map_yaml_file_is_one_line_naming_entry_and_file(tmp_path, content, expected):
    (tmp_path / "m.yaml").write_text(content)
    p = write(tmp_path, "maps:\n  - map: m.yaml\n    start: [0.5, 0.5]\n    goal: [2.5, 0.5]\n"
                        "planners: [xsweep]\n")
    with pytest.raises(ConfigError) as ei:
        load_experiment(p)
    msg = str(ei.value)
    assert "\n" not in msg and msg.startswith(f"{p}: maps[0].map: ") and "m.yaml" in msg
    assert expected in msg, msg


def test_canonical_json_normalises_types():
    import numpy as np

    assert canonical_json({"b": (1, 2), "a": np.float32(0.5), "c": np.int64(3)}) == \
        '{"a":0.5,"b":[1,2],"c":3}'
    with pytest.raises(ValueError):
        canonical_json({"x": float("nan")})


def test_shipped_experiments_are_valid():
    files = sorted((REPO / "experiments").glob("*.yaml"))
    assert len(files) >= 4
    for f in files:
        if "../shared/" in f.read_text() and not SHARED.is_dir():
            continue  # the big data set lives next to the repository, not in it
        if f.name.startswith("barn-"):  # a BARN experiment file, run by `pathfuse barn`
            from pathfuse.studies.barn import find_worlds, load_barn_file

            cfg, _ = load_barn_file(f)
            assert len(find_worlds(cfg.directory, cfg.worlds)) == 250
            continue
        exp = load_experiment(f, seeds=2, check_maps=True)
        has_dynamic = any(m.kind == "dynamic" for m in exp.maps)
        if not has_dynamic:
            assert exp.expand()
