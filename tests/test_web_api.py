"""The JSON API of ``pathfuse serve``, through Starlette's test client: every endpoint and
every error path.  Answers are checked against the library and the command line."""

from __future__ import annotations

import base64
import dataclasses
import io
import json
import math
import shutil
import time
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest
import yaml

with warnings.catch_warnings():  # starlette suggests httpx2, a fork; httpx works
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient

import pathfuse
from pathfuse.cli import main
from pathfuse.validate import param_spec
from pathfuse.web.app import create_app
from pathfuse.web.maps import Limits, grid_from_bits, grid_to_json

DATA = Path(__file__).parent / "data"
ROOT = Path(__file__).resolve().parents[1]
ROS = DATA / "ros" / "nav2_tb3_sandbox"
BASE = "http://127.0.0.1"  # the server answers loopback Host names only (by default)


@pytest.fixture(scope="module")
def client():
    # the server's other limits at their defaults, but a request budget that a first
    # request's compilation on an empty numba cache cannot exceed on a loaded machine
    # (the default 8 s of wall time did, at load 8-13 on 2 cores: a 503 instead of the
    # answer); the budget itself is tested with apps of their own
    # (test_a_request_over_the_budget_is_503)
    with TestClient(create_app(limits=Limits(time_budget_s=120.0)), base_url=BASE) as c:
        yield c


def unpack(d, key="bits"):
    n = d["width"] * d["height"]
    raw = np.frombuffer(base64.b64decode(d[key]), dtype=np.uint8)
    return np.unpackbits(raw, count=n).astype(bool).reshape(d["height"], d["width"])


def cli_json(capsys, *argv):
    capsys.readouterr()
    main(list(argv))
    return json.loads(capsys.readouterr().out)


def cli_error(capsys, *argv):
    capsys.readouterr()
    code = main(list(argv))
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.count("\n") == 0
    prefix = f"pathfuse {argv[0]}: error: "
    assert err.startswith(prefix)
    return err[len(prefix):]


# --------------------------------------------------------------------------- page
def test_page_and_its_files(client):
    r = client.get("/")
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/html")
    for name in ("main.js", "view.js", "api.js", "forms.js", "episode.js", "style.css"):
        assert f"{name}" in r.text or name != "style.css"
        s = client.get(f"/static/{name}")
        assert s.status_code == 200, name
        assert "http://" not in s.text and "https://" not in s.text  # no CDN, no network
    assert client.get("/static/main.js").headers["content-type"].startswith("text/javascript")


@pytest.mark.parametrize("path", ["/static/../app.py", "/static/%2e%2e%2fapp.py",
                                  "/static/app.py", "/static/..%2F..%2Fpyproject.toml",
                                  "/static//etc/passwd", "/etc/passwd"])
def test_no_file_named_by_a_request_is_served(client, path):
    r = client.get(path)
    assert r.status_code == 404
    assert "import" not in r.text and "root:" not in r.text


def test_unknown_endpoint_and_wrong_method(client):
    r = client.get("/api/nope")
    assert r.status_code == 404 and "no such endpoint" in r.json()["error"]
    r = client.get("/api/plan")
    assert r.status_code == 405 and r.json()["error"] == "method GET not allowed on /api/plan"


# --------------------------------------------------------------------------- planners
def test_planners_loop_over_the_registry(client):
    got = client.get("/api/planners").json()
    assert [p["name"] for p in got] == pathfuse.planner_names()
    for p in got:
        spec = pathfuse.get_planner(p["name"])
        fields = dataclasses.fields(spec.params_cls)
        assert [q["name"] for q in p["params"]] == [f.name for f in fields]
        defaults = spec.params_cls()
        for q, f in zip(p["params"], fields, strict=True):
            assert q["default"] == getattr(defaults, q["name"])
            assert q["kind"] in ("float", "int", "bool", "choice", "str")
            ps = param_spec(f)
            if q["name"] == "global_planner":  # a choice among the registered ones
                assert q["kind"] == "choice" and q["choices"] == pathfuse.global_planner_names()
                assert q["help"] == ps.help
            elif ps is not None:  # declared with param(): its metadata (plug-ins may not)
                assert q["help"] == ps.help and q["unit"] == ps.unit and q["kind"] == ps.kind
        assert ("closed" in p["layers"]) == spec.uses_astar
    fusion = next(p for p in got if p["name"] == "fusion")
    r1 = next(q for q in fusion["params"] if q["name"] == "r1_m")
    assert r1["unit"] == "m" and r1["gt"] == 0 and r1["le"] == 100
    assert r1["accepts"] == "number > 0 and <= 100 m"
    ahead = next(q for q in fusion["params"] if q["name"] == "ahead")
    assert ahead["kind"] == "choice" and ahead["choices"] == ["progress", "paper-x"]
    assert "attractors" in fusion["layers"]


def test_a_plugin_planner_appears_and_plans(client):
    from pathfuse.planners.params import Checked
    from pathfuse.validate import param

    @dataclasses.dataclass(frozen=True)
    class P(Checked):
        gain: float = param(1.5, gt=0, unit="m", help="a gain")

    def straight(grid, start, goal, params, budget):
        path = np.array([start, goal])
        return pathfuse.PlanResult(pathfuse.Status.SUCCESS, path,
                                   float(np.hypot(*(goal - start))), planner="straight")

    pathfuse.register_function("straight", straight, P, "a straight line")
    got = client.get("/api/planners").json()
    assert got[-1]["name"] == "straight" and got[-1]["params"][0]["unit"] == "m"
    r = client.post("/api/plan", json={"map": "paper", "planner": "straight",
                                       "params": {"gain": 2}})
    assert r.status_code == 200 and r.json()["length"] == pytest.approx(10 * math.sqrt(2))
    r = client.post("/api/plan", json={"map": "paper", "planner": "straight",
                                       "params": {"gain": -1}})
    assert r.status_code == 400 and r.json()["error"] == \
        "straight.gain: must be a number > 0, got -1"


# --------------------------------------------------------------------------- maps
def test_catalog_lists_the_example_and_test_maps(client):
    d = client.get("/api/maps").json()
    ids = [m["id"] for m in d["maps"]]
    assert ids[0] == "paper"
    assert "tests/data/movingai/den312d.map" in ids
    assert "tests/data/ros/nav2_tb3_sandbox/tb3_sandbox.yaml" in ids
    assert d["limits"]["max_cells"] == Limits().max_cells


@pytest.mark.parametrize("map_id, path", [
    ("tests/data/movingai/den312d.map", DATA / "movingai" / "den312d.map"),
    ("tests/data/ros/nav2_tb3_sandbox/tb3_sandbox.yaml", ROS / "tb3_sandbox.yaml"),
])
def test_a_catalog_map_as_json(client, map_id, path):
    d = client.get(f"/api/maps/{map_id}").json()
    g = pathfuse.load_map(path)
    assert (d["width"], d["height"]) == (g.width, g.height)
    assert d["resolution"] == g.resolution and d["origin"] == list(g.origin)
    assert np.array_equal(unpack(d), g.occupied)


@pytest.mark.parametrize("map_id", ["nope.map", "/etc/passwd", "../../pyproject.toml",
                                    "tests/data/movingai/SOURCES.md"])
def test_unknown_map_ids_are_404(client, map_id):
    r = client.get(f"/api/maps/{map_id}")
    assert r.status_code == 404 and "[tool" not in r.text
    r = client.post("/api/plan", json={"map": {"id": map_id}, "start": [1, 1], "goal": [2, 2]})
    assert r.status_code == 404


def test_map_from_specs(client):
    d = client.post("/api/map", json={"map": "paper", "seed": 4}).json()
    assert np.array_equal(unpack(d), pathfuse.load_map("paper", seed=4).occupied)
    assert d["spec"] == {"paper": {"seed": 4}} and d["id"].startswith("upload-")
    d2 = client.get(f"/api/maps/{d['id']}").json()  # kept under its id
    assert d2["bits"] == d["bits"]
    d = client.post("/api/map", json={"map": {"blank": {"size": [7, 3], "resolution": 0.5}}}
                    ).json()
    assert (d["width"], d["height"], d["resolution"]) == (7, 3, 0.5) and not unpack(d).any()
    d = client.post("/api/map", json={"map": {"rows": ["..#", "..."]}}).json()
    assert unpack(d).tolist() == [[False] * 3, [False, False, True]]


@pytest.mark.parametrize("body, status, message", [
    ({"map": {"blank": {"size": [5000, 5000]}}}, 413, "map.blank: 5000 x 5000 = 25000000 cells"),
    ({"map": {"random": {"size": [3000, 3000], "obstacles": 1}}}, 413, "map.random: 3000 x 3000"),
    ({"map": {"rows": ["." * 3000] * 1500}}, 413, "map.rows: 3000 x 1500"),
    ({"map": {"blank": {"size": [0, 5]}}}, 400, "map.blank.size[0]: must be an integer >= 1"),
    ({"map": {"movingai": "/etc/passwd"}}, 400, "map.movingai: the server reads no file"),
    ({"map": {"image": "x.png", "resolution": 1}}, 400, "map.image: the server reads no file"),
    ({"map": 5}, 400, "map: must be 'paper', a map id or a map spec mapping, got 5"),
    ({"map": {"paper": {"seed": -1}}}, 400, "map: map spec 'paper' seed must be"),
    ({"map": "paper", "seed": "x"}, 400, "seed: must be an integer >= 0, got 'x'"),
    ({}, 400, "map: missing"),
    ({"map": "paper", "colour": 1}, 400, "colour: unknown key (allowed: map, seed)"),
])
def test_map_spec_errors(client, body, status, message):
    r = client.post("/api/map", json=body)
    assert r.status_code == status and r.json()["error"].startswith(message), r.json()


def test_an_edited_grid_round_trips():
    g = pathfuse.load_map(DATA / "movingai" / "maze-32-32-2.map")
    assert np.array_equal(grid_from_bits(grid_to_json(g)).occupied, g.occupied)


@pytest.mark.parametrize("grid, message", [
    ({"width": 4, "height": 2, "bits": "AAA="}, "map.grid.bits: must hold 1 bytes for 4 x 2"),
    ({"width": 4, "height": 2, "bits": "!!"}, "map.grid.bits: not valid base64"),
    ({"width": 4, "height": 2, "bits": 5}, "map.grid.bits: must be a base64 string"),
    ({"width": 4, "bits": "AA=="}, "map.grid.height: must be an integer >= 1, got None"),
    ({"width": 4, "height": 2, "bits": "AA==", "resolution": 0}, "map.grid.resolution: must"),
    ({"width": 4, "height": 2, "bits": "AA==", "x": 1}, "map.grid.x: unknown key"),
    ({"width": 4, "height": 2, "bits": "A" * 1000}, "map.grid.bits: longer than 4 x 2"),
])
def test_edited_grid_errors(client, grid, message):
    r = client.post("/api/plan", json={"map": {"grid": grid}, "start": [0.5, 0.5],
                                       "goal": [1.5, 0.5]})
    assert r.status_code == 400 and r.json()["error"].startswith(message), r.json()


# --------------------------------------------------------------------------- plan
@pytest.mark.parametrize("planner", ["astar", "fusion", "apf"])
def test_plan_answers_the_cli_json(client, capsys, planner):
    api = client.post("/api/plan", json={"map": "paper", "seed": 5, "start": [1, 1],
                                         "goal": [11, 11], "planner": planner, "params": {}})
    assert api.status_code == 200
    cli = cli_json(capsys, "plan", "--map", "paper", "--seed", "5", "--planner", planner,
                   "--json")
    a, c = api.json(), cli
    assert a.pop("time_s") >= 0 and c.pop("time_s") >= 0
    assert a == c


def test_plan_on_a_catalog_ros_map_equals_the_cli(client, capsys):
    body = {"map": {"id": "tests/data/ros/nav2_tb3_sandbox/tb3_sandbox.yaml"},
            "start": [-1.0, -0.5], "goal": [1.5, 0.5], "robot_radius": 0.1, "planner": "fusion"}
    a = client.post("/api/plan", json=body).json()
    c = cli_json(capsys, "plan", "--map", str(ROS / "tb3_sandbox.yaml"), "--start", "-1.0,-0.5",
                 "--goal", "1.5,0.5", "--robot-radius", "0.1", "--planner", "fusion", "--json")
    a.pop("time_s"), c.pop("time_s")
    assert a == c and a["status"] == "SUCCESS"


def test_plan_on_an_edited_grid(client):
    g = pathfuse.GridMap.from_rows(["......", ".####.", "......"], name="edited")
    body = {"map": {"grid": grid_to_json(g)}, "start": [0.5, 1.5], "goal": [5.5, 1.5]}
    d = client.post("/api/plan", json=body).json()
    ref = pathfuse.plan(g, (0.5, 1.5), (5.5, 1.5))
    assert d["status"] == "SUCCESS" and d["length"] == pytest.approx(ref.length)
    assert d["path"] == ref.path.tolist() and d["map"] == "edited"


def test_plan_extras_and_layers(client):
    from pathfuse.metrics import evaluate

    g = pathfuse.load_map("paper", seed=5)
    body = {"map": "paper", "seed": 5, "planner": "fusion", "robot_radius": 0.2,
            "layers": ["closed", "cspace", "attractors"]}
    d = client.post("/api/plan", json=body).json()
    res = pathfuse.plan(g, (1, 1), (11, 11), "fusion", robot_radius_m=0.2)
    ex = d["extras"]
    m = evaluate(g, res, 0.2)
    assert ex["min_clearance_m"] == pytest.approx(m["min_clearance_m"])
    assert ex["collision_free"] is True
    assert ex["astar_path"] == res.info["astar_path"].tolist()
    shaped = {"width": g.width, "height": g.height}
    closed = unpack({**shaped, "bits": ex["closed"]["bits"]})
    assert ex["closed"]["count"] == d["expansions"] == int(closed.sum()) > 0
    cells = g.world_to_cell(res.info["astar_path"])
    assert closed[cells[:-1, 0], cells[:-1, 1]].all()  # the path runs through closed cells
    assert not (closed & g.cspace(0.2).occupied).any()
    cs = unpack({**shaped, "bits": ex["cspace"]["bits"]})
    assert np.array_equal(cs, g.cspace(0.2).occupied)
    at = ex["attractors"]
    assert at["r1_m"] == 2.0 and len(at["per_point"]) == len(d["path"])
    wp = np.array(at["waypoints"])
    assert wp[-1].tolist() == [11.0, 11.0]
    for p, idx in zip(d["path"], at["per_point"], strict=True):
        for j in idx:
            assert math.dist(p, wp[j]) < 2.0
    assert sum(map(len, at["per_point"])) > 0


def test_plan_closed_set_of_astar_counts_its_expansions(client):
    for heuristic in ("euclidean", "octile"):
        d = client.post("/api/plan", json={"map": {"id": "tests/data/movingai/den312d.map"},
                                           "start": [10.5, 70.5], "goal": [60.5, 8.5],
                                           "params": {"heuristic": heuristic},
                                           "layers": ["closed"]}).json()
        assert d["status"] == "SUCCESS"
        closed = unpack({"width": 81, "height": 65, "bits": d["extras"]["closed"]["bits"]})
        assert int(closed.sum()) == d["expansions"]


def test_a_failed_query_is_a_status_not_an_error(client):
    d = client.post("/api/plan", json={"map": {"rows": [".#."]}, "start": [1.5, 0.5],
                                       "goal": [2.5, 0.5], "layers": ["closed"]})
    assert d.status_code == 200
    assert d.json()["status"] == "START_OCCUPIED" and d.json()["extras"]["closed"] is None
    d = client.post("/api/plan", json={"map": {"rows": [".#."]}, "start": [0.5, 0.5],
                                       "goal": [2.5, 0.5]}).json()
    assert d["status"] == "NO_PATH"


def test_plan_has_a_time_budget(client):
    # a 1024 x 1024 maze-like map and a 1 ms limit: the planner stops with TIMEOUT
    ends = [[0.5, 0.5], [1023.5, 1023.5]]
    body = {"map": {"random": {"size": [1024, 1024], "density": 0.3, "seed": 1,
                               "keep_free": ends, "connect": [ends]}},
            "start": ends[0], "goal": ends[1], "time_limit": 0.001}
    d = client.post("/api/plan", json=body).json()
    assert d["status"] == "TIMEOUT" and "time_limit" in d["message"]


@pytest.mark.parametrize("argv, body", [
    (["--planner", "nope"], {"planner": "nope"}),
    (["--planner", "fusion", "--param", "r1_m=-1"], {"planner": "fusion",
                                                    "params": {"r1_m": -1}}),
    (["--planner", "fusion", "--param", "ahead=behind"], {"planner": "fusion",
                                                         "params": {"ahead": "behind"}}),
    (["--planner", "astar", "--param", "r9=1"], {"planner": "astar", "params": {"r9": 1}}),
])
def test_plan_errors_say_what_the_cli_says(client, capsys, argv, body):
    r = client.post("/api/plan", json={"map": "paper", **body})
    assert r.status_code == 400
    assert r.json()["error"] == cli_error(capsys, "plan", "--map", "paper", *argv)


@pytest.mark.parametrize("body, message", [
    ({"map": "paper", "start": "1,1"}, "start: must be two numbers [x, y], got '1,1'"),
    ({"map": "paper", "goal": [1, "x"]}, "goal[1]: must be a number, got 'x'"),
    ({"map": {"rows": ["..."]}}, "start and goal are required unless map is 'paper'"),
    ({"map": "paper", "robot_radius": -1}, "robot_radius: must be a number >= 0, got -1"),
    ({"map": "paper", "time_limit": 0}, "time_limit: must be a number > 0, got 0"),
    ({"map": "paper", "params": [1]}, "params: must be a mapping, got [1]"),
    ({"map": "paper", "layers": ["x"]}, "layers: must be a list of 'closed', 'cspace'"),
    ({"map": "paper", "extras": "yes"}, "extras: must be true or false, got 'yes'"),
    ({"map": "paper", "speed": 1}, "speed: unknown key (allowed: map, seed, start, goal"),
    ({"map": "paper", "planner": 3}, "planner: must be a string, got 3"),
    ([1, 2], "request: must be a JSON object, got [1, 2]"),
])
def test_plan_bad_input(client, body, message):
    r = client.post("/api/plan", json=body)
    assert r.status_code == 400 and r.json()["error"].startswith(message), r.json()


def test_bodies_that_are_not_json_or_too_big():
    with TestClient(create_app(limits=Limits(max_body_bytes=1000)), base_url=BASE) as c:
        r = c.post("/api/plan", content=b"{not json", headers={"content-type": "application/json"})
        assert r.status_code == 400 and r.json()["error"].startswith("request body: not valid JSON")
        r = c.post("/api/plan", content=b"\xff\xfe", headers={"content-type": "application/json"})
        assert r.status_code == 400
        r = c.post("/api/plan", json={"map": {"rows": ["." * 2000]}})
        assert r.status_code == 413 and "limit of 1000" in r.json()["error"]


# --------------------------------------------------------------------------- budget, threads
def _sleepy(seconds):
    from pathfuse.planners.params import Checked
    from pathfuse.validate import param

    @dataclasses.dataclass(frozen=True)
    class P(Checked):
        nap_s: float = param(seconds, gt=0, unit="s", help="how long to sleep")

    def nap(grid, start, goal, params, budget):
        time.sleep(params.nap_s)
        return pathfuse.PlanResult(pathfuse.Status.SUCCESS, np.array([start, goal]), 1.0,
                                   planner="nap")

    pathfuse.register_function("nap", nap, P, "sleeps")


def test_a_planner_that_raises_is_a_500_with_its_message(client):
    from pathfuse.planners.params import Checked

    @dataclasses.dataclass(frozen=True)
    class P(Checked):
        pass

    def broken(grid, start, goal, params, budget):
        raise RuntimeError("plug-in bug")

    pathfuse.register_function("broken", broken, P, "raises")
    r = client.post("/api/plan", json={"map": "paper", "planner": "broken"})
    assert r.status_code == 500
    assert r.json()["error"] == "internal error: RuntimeError: plug-in bug"
    assert client.post("/api/plan", json={"map": "paper"}).status_code == 200  # still serving


def test_a_request_over_the_budget_is_503():
    _sleepy(1.5)
    with TestClient(create_app(limits=Limits(time_budget_s=0.1, grace_s=0.2)),
                    base_url=BASE) as c:
        t0 = time.perf_counter()
        r = c.post("/api/plan", json={"map": "paper", "planner": "nap"})
        assert time.perf_counter() - t0 < 1.2
        assert r.status_code == 503 and "budget of 0.1 s" in r.json()["error"]


def test_planners_run_off_the_event_loop():
    import asyncio

    import httpx

    _sleepy(1.0)
    app = create_app()

    async def run():
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(transport=transport, base_url=BASE) as c:
            done = {}

            async def slow():
                await c.post("/api/plan", json={"map": "paper", "planner": "nap"})
                done["slow"] = time.perf_counter()

            async def fast():
                await asyncio.sleep(0.1)
                r = await c.get("/api/maps")
                assert r.status_code == 200
                r = await c.post("/api/map", json={"map": "paper"})
                assert r.status_code == 200
                done["fast"] = time.perf_counter()

            await asyncio.gather(slow(), fast())
            return done

    done = asyncio.run(run())
    assert done["fast"] < done["slow"] - 0.3


# --------------------------------------------------------------------------- field
def test_field_matches_the_planners_kernels(client):
    from pathfuse.costmap import make_costmap
    from pathfuse.field.repulsion import apf_force, grid_rep_potential

    g = pathfuse.load_map("paper", seed=5)
    cm = make_costmap(g.occupied, 0.0, origin=(-0.5, -0.5), lattice=False)
    d = client.post("/api/field", json={"map": "paper", "seed": 5, "goal": [11, 11],
                                        "planner": "fusion", "params": {"k_rep": 7}}).json()
    assert d["params"] == {"k_att": 40.0, "k_rep": 7.0, "rho0_m": 2.0}
    h = d["heat"]
    assert h["shape"] == [15, 15]
    att = np.frombuffer(base64.b64decode(h["attractive"]), "<f4").reshape(15, 15)
    rep = np.frombuffer(base64.b64decode(h["repulsive"]), "<f4").reshape(15, 15)
    assert np.array_equal(np.isnan(rep), g.occupied) and np.array_equal(np.isnan(att),
                                                                          g.occupied)
    for r in range(15):
        for c in range(15):
            if g.occupied[r, c]:
                continue
            x, y = h["xs"][c], h["ys"][r]
            assert rep[r, c] == pytest.approx(grid_rep_potential(x, y, cm, 7.0, 2.0),
                                              rel=1e-6, abs=1e-6)
            assert att[r, c] == pytest.approx(20.0 * ((x - 11) ** 2 + (y - 11) ** 2), rel=1e-6)
    a = d["arrows"]
    i, j = 3, 4
    fx, fy = apf_force(a["xs"][j], a["ys"][i], 11.0, 11.0, 40.0, 7.0, 2.0, 2.0, cm)
    assert a["fx"][i][j] == pytest.approx(fx) and a["fy"][i][j] == pytest.approx(fy)


def test_field_on_a_large_map_is_sampled(client):
    d = client.post("/api/field", json={"map": {"blank": {"size": [1024, 700]}},
                                        "goal": [500, 300], "max_side": 128, "arrows": 16}
                    ).json()
    assert d["heat"]["shape"] == [128, 128] and d["arrows"]["shape"] == [16, 16]
    assert d["heat"]["max_repulsive"] == 0.0 and d["planner"] == "apf"


@pytest.mark.parametrize("body, message", [
    ({"map": {"rows": ["..."]}}, "goal: missing"),
    ({"map": "paper", "max_side": 4096}, "max_side: must be an integer >= 2 and <= 512"),
    ({"map": "paper", "arrows": 1}, "arrows: must be an integer >= 2 and <= 64"),
    ({"map": "paper", "planner": "apf", "params": {"k_att": 0}},
     "apf.k_att: must be a number > 0, got 0"),
    ({"map": "paper", "start": [1, 1]}, "start: unknown key"),
])
def test_field_bad_input(client, body, message):
    r = client.post("/api/field", json=body)
    assert r.status_code == 400 and r.json()["error"].startswith(message), r.json()


# --------------------------------------------------------------------------- episodes
def test_catalog_scenarios_and_simulate_equal_the_library(client):
    ids = [s["id"] for s in client.get("/api/scenarios").json()["scenarios"]]
    assert "examples/scenarios/head_on.yaml" in ids
    assert not any("bad_" in i or "duplicate" in i for i in ids)  # only those that load
    d = client.get("/api/scenarios/examples/scenarios/head_on.yaml").json()
    sc = d["scenario"]
    assert sc["map"]["id"] == d["map"]["id"] and len(sc["obstacles"]) == 1
    for planner in ("fusion", "astar"):
        ep = client.post("/api/simulate", json={"scenario": sc, "planner": planner}).json()
        ref = pathfuse.simulate(ROOT / "examples" / "scenarios" / "head_on.yaml",
                                planner=planner)
        assert ep["status"] == ref.status.name and ep["n_ticks"] == ref.n_ticks
        assert ep["positions"] == ref.positions.tolist()
        assert len(ep["obstacle_positions"]) == ep["n_ticks"] + 1 == len(ep["sensed"])
        assert ep["robot"]["sensing_radius"] == 3.0
    assert client.get("/api/scenarios/nope.yaml").status_code == 404


def _scene(**over):
    sc = {"map": "paper", "start": [1, 1], "goal": [11, 11],
          "obstacles": [{"position": [6, 2], "velocity": [-0.3, 0.4], "radius": 0.3}],
          "planner": {"name": "fusion", "params": {}}}
    sc.update(over)
    return sc


@pytest.mark.parametrize("scene, status, message", [
    (_scene(obstacles=[{"position": [6, 2], "velocity": [0, 0], "radius": 0.3}] * 70), 413,
     "obstacles: 70 discs is more than this server's limit of 64"),
    (_scene(time_limit=1e6), 413, "time_limit / dt = 10000000 ticks"),
    (_scene(obstacles=[{"position": [6, 2], "speed": "fast"}]), 400, "scenario.obstacles[0]"),
    (_scene(planner="nope"), 400, "scenario.planner.name: unknown planner 'nope'"),
    (_scene(start=[1, "a"]), 400, "scenario.start[1]: must be a number"),
    (_scene(map={"ros": "/etc/x.yaml"}), 400, "scenario.map.ros: the server reads no file"),
    (_scene(colour=1), 400, "scenario.colour: unknown key"),
])
def test_simulate_bad_input(client, scene, status, message):
    r = client.post("/api/simulate", json={"scenario": scene})
    assert r.status_code == status and r.json()["error"].startswith(message), r.json()


def test_simulate_request_errors(client):
    r = client.post("/api/simulate", json={"planner": "fusion"})
    assert r.status_code == 400 and r.json()["error"] == "scenario: missing"
    r = client.post("/api/simulate", json={"scenario": _scene(), "seed": -2})
    assert r.status_code == 400 and r.json()["error"].startswith("seed: must be an integer")
    r = client.post("/api/simulate", json={"scenario": _scene(), "planner": {"name": "x"}})
    assert r.status_code == 400 and "unknown planner 'x'" in r.json()["error"]


@pytest.mark.parametrize("map_spec, key", [("paper", "paper"), ("edited", "rows")])
def test_export_runs_unchanged_in_pathfuse_simulate(client, capsys, tmp_path, map_spec, key):
    if map_spec == "edited":
        g = pathfuse.load_map("paper", seed=0).occupied.copy()
        g[5, 3] = True
        grid = grid_to_json(pathfuse.GridMap(g, 1.0, (-0.5, -0.5), name="mine"))
        scene = _scene(map={"grid": grid})
    else:
        scene = _scene()
    ep = client.post("/api/simulate", json={"scenario": scene}).json()
    d = client.post("/api/scenario/export", json={"scenario": scene}).json()
    assert d["filename"] == "scenario.yaml" and f"\n  {key}:" in "\n" + d["yaml"] or \
        d["yaml"].count(key)
    path = tmp_path / d["filename"]
    path.write_text(d["yaml"])
    cli = cli_json(capsys, "simulate", str(path), "--json")
    assert cli["status"] == ep["status"] and cli["n_ticks"] == ep["n_ticks"]
    assert cli["path_length_m"] == pytest.approx(ep["path_length_m"])
    r = client.post("/api/scenario/export", json={"scenario": _scene(dt=0)})
    assert r.status_code == 400 and r.json()["error"].startswith("scenario.dt: must be")


def test_export_writes_the_robot_keys_set_and_replays_exactly(client, capsys, tmp_path):
    robot = {"model": "diff-drive", "max_yaw_rate": 1.5}          # the rest unset
    scene = _scene(robot=robot, planner={"name": "dwa", "params": {}})
    ep = client.post("/api/simulate", json={"scenario": scene}).json()
    d = client.post("/api/scenario/export", json={"scenario": scene}).json()
    assert yaml.safe_load(d["yaml"])["robot"] == robot
    path = tmp_path / d["filename"]
    path.write_text(d["yaml"])
    from pathfuse.world import load_scenario

    assert load_scenario(path).robot == pathfuse.RobotModel.from_dict(robot)
    cli = cli_json(capsys, "simulate", str(path), "--json", "--trajectories")
    assert cli["positions"] == ep["positions"] and cli["commands"] == ep["commands"]
    assert ep["robot"] == {"radius": 0.2, "max_speed": 1.0, "sensing_radius": 3.0}


def test_scenario_uploads(client):
    text = (ROOT / "examples" / "scenarios" / "crossing.yaml").read_bytes()
    d = client.post("/api/scenarios", files={"file": ("crossing.yaml", text)}).json()
    assert d["scenario"]["name"] == "crossing" and len(d["scenario"]["obstacles"]) == 3
    bad = (b"map: paper\nstart: [1, 1]\ngoal: [11, 11]\nobstacles:\n"
           b"  - {position: [6, 2], speed: x\n")
    r = client.post("/api/scenarios", files={"file": ("bad.yaml", bad)})
    assert r.status_code == 400 and r.json()["error"].startswith("bad.yaml: line ")
    assert "pathfuse-scenario" not in r.json()["error"]  # no server path in the message
    ref = b"map: {movingai: /etc/passwd}\nstart: [1, 1]\ngoal: [2, 2]\n"
    r = client.post("/api/scenarios", files={"file": ("ref.yaml", ref)})
    assert r.status_code == 400 and "reads no file a scenario names" in r.json()["error"]
    r = client.post("/api/scenarios", files={"file": ("d.yaml", b"map: paper\nmap: paper\n")})
    assert r.status_code == 400 and "duplicate key" in r.json()["error"]


# --------------------------------------------------------------------------- uploads
def _upload(client, *files, **fields):
    return client.post("/api/maps", files=[("file", f) for f in files], data=fields)


def test_upload_every_format(client, tmp_path):
    from PIL import Image

    den = DATA / "movingai" / "den312d.map"
    d = _upload(client, ("den312d.map", den.read_bytes())).json()
    assert np.array_equal(unpack(d), pathfuse.load_map(den).occupied)
    assert client.get(f"/api/maps/{d['id']}").json()["bits"] == d["bits"]
    ros = pathfuse.load_map(ROS / "tb3_sandbox.yaml")
    pair = [("tb3_sandbox.yaml", (ROS / "tb3_sandbox.yaml").read_bytes()),
            ("tb3_sandbox.pgm", (ROS / "tb3_sandbox.pgm").read_bytes())]
    d = _upload(client, *pair).json()
    assert np.array_equal(unpack(d), ros.occupied) and d["origin"] == list(ros.origin)
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for name, data in pair:
            z.writestr(f"maps/{name}", data)
    d = _upload(client, ("sandbox.zip", buf.getvalue())).json()
    assert np.array_equal(unpack(d), ros.occupied)
    img = np.full((6, 9), 255, dtype=np.uint8)
    img[2, 3] = 0
    Image.fromarray(img).save(tmp_path / "room.png")
    d = _upload(client, ("room.png", (tmp_path / "room.png").read_bytes()),
                resolution="0.25").json()
    assert (d["width"], d["height"], d["resolution"]) == (9, 6, 0.25) and unpack(d)[3, 3]
    arr = np.zeros((4, 5), dtype=bool)
    arr[1, 2] = True
    np.save(tmp_path / "a.npy", arr)
    d = _upload(client, ("a.npy", (tmp_path / "a.npy").read_bytes()), resolution="1").json()
    assert np.array_equal(unpack(d), arr)
    rows = b"rows:\n  - '....'\n  - '.##.'\nresolution: 0.5\n"
    d = _upload(client, ("inline.yaml", rows)).json()
    assert unpack(d).sum() == 2 and d["resolution"] == 0.5


@pytest.mark.parametrize("files, fields, status, message", [
    ([("broken.map", b"type octile\nheight 3\nwidth x\nmap\n...\n")], {}, 400, "broken.map"),
    ([("room.txt", b"hello")], {}, 400, "expected one map file"),
    ([("room.png", b"not a png")], {"resolution": "1"}, 400, "room.png: not a readable image"),
    ([("a.npy", b"\x93NUMPY junk")], {"resolution": "1"}, 400, "a.npy: not a readable .npy"),
    ([("x.zip", b"PK junk")], {}, 400, "x.zip: not a valid zip file"),
    ([("tb3.yaml", (ROS / "tb3_sandbox.yaml").read_bytes())], {}, 400,
     "tb3.yaml: image 'tb3_sandbox.pgm' was not uploaded with it"),
    ([("evil.yaml", b"image: /etc/hostname\nresolution: 1\norigin: [0, 0, 0]\n"
                    b"occupied_thresh: 0.65\nfree_thresh: 0.2\nnegate: 0\n")], {}, 400,
     "evil.yaml: image '/etc/hostname' was not uploaded with it"),
    ([("a.map", b"x"), ("b.map", b"y")], {}, 400, "expected one map file"),
    ([("den.map", (DATA / "movingai" / "den312d.map").read_bytes())], {"resolution": "-1"},
     400, "resolution: must be a number > 0, got '-1'"),
])
def test_upload_errors(client, files, fields, status, message):
    r = _upload(client, *files, **fields)
    assert r.status_code == status and message in r.json()["error"], r.json()
    assert "pathfuse-upload" not in r.json()["error"]


def test_upload_of_an_image_without_resolution_says_so(client, tmp_path):
    from PIL import Image

    Image.fromarray(np.full((4, 4), 255, dtype=np.uint8)).save(tmp_path / "r.png")
    r = _upload(client, ("r.png", (tmp_path / "r.png").read_bytes()))
    assert r.status_code == 400 and "resolution" in r.json()["error"]


def test_upload_limits(tmp_path):
    from PIL import Image

    with TestClient(create_app(limits=Limits(max_upload_bytes=5000, max_cells=1000)),
                    base_url=BASE) as c:
        big = (DATA / "movingai" / "den312d.map").read_bytes()
        r = _upload(c, ("den312d.map", big))
        assert r.status_code == 413 and "limit of 5000 bytes" in r.json()["error"]
        head = b"type octile\nheight 100\nwidth 100\nmap\n" + b"." * 100
        r = _upload(c, ("h.map", head))
        assert r.status_code == 413 and "100 x 100 = 10000 cells" in r.json()["error"]
        Image.fromarray(np.zeros((200, 200), dtype=np.uint8)).save(tmp_path / "b.png")
        r = _upload(c, ("b.png", (tmp_path / "b.png").read_bytes()), resolution="1")
        assert r.status_code == 413 and "200 x 200" in r.json()["error"]
        r = c.post("/api/maps", content=b"raw", headers={"content-type": "text/plain"})
        assert r.status_code == 415
        buf = io.BytesIO()
        with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("zeros.map", b"\0" * 200_000)  # a small zip that unpacks big
        r = _upload(c, ("bomb.zip", buf.getvalue()))
        assert r.status_code == 413 and "unpacks to 200000 bytes" in r.json()["error"]


def test_serve_binds_loopback_by_default_and_answers(tmp_path):
    import os
    import socket
    import subprocess
    import sys
    import urllib.request

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen([sys.executable, "-m", "pathfuse.cli", "serve", "--port", str(port),
                             "--no-warm"], stderr=subprocess.PIPE, text=True, env=env)
    try:
        line = proc.stderr.readline()
        assert line.strip() == f"pathfuse serve: http://127.0.0.1:{port}/  (Ctrl-C stops it)"
        for _ in range(100):
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/maps", timeout=2) as r:
                    assert json.loads(r.read())["maps"][0]["id"] == "paper"
                break
            except OSError:
                time.sleep(0.1)
        else:
            raise AssertionError("the server did not answer")
        out = subprocess.run(["ss", "-ltn"], capture_output=True, text=True) \
            if shutil.which("ss") else None
        if out is not None and out.returncode == 0:
            listening = [x for x in out.stdout.split() if x.endswith(f":{port}")]
            assert listening == [f"127.0.0.1:{port}"]
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def test_serve_without_the_extra_says_how_to_get_it(monkeypatch, capsys):
    import builtins

    real = builtins.__import__

    def no_uvicorn(name, *a, **k):
        if name == "uvicorn":
            raise ImportError("no uvicorn", name="uvicorn")
        return real(name, *a, **k)

    monkeypatch.setattr(builtins, "__import__", no_uvicorn)
    assert cli_error(capsys, "serve") == \
        'the web app needs its extra: pip install "pathfuse[web]" (uvicorn is missing)'
