"""``pathfuse serve`` probed as an attacker would: the hostile-request suite of issue 19.

* No request reads a file it names: every way a request can name a path (map sources
  of every kind, ids, scenario files, ROS images, zip members), for a path that exists
  and one that does not, gives the same answer, and an audit hook in the server and
  its worker processes sees no file opened outside the shipped maps, the uploads'
  temporary folders and Python's own files.
* The cell limit is checked before a grid is allocated (Gazebo worlds too), decompression
  bombs are 413, planner parameters have upper bounds.
* Slow work runs in worker processes that are killed at the deadline (their CPU stops),
  the queue is bounded (503 + Retry-After), the catalog and the page stay served while
  the workers are busy, and a short plan is answered while two slow ones run.
* Only JSON bodies (415), only loopback Host names by default, no foreign Origin, no JSON
  nested too deep.
* The command line: ``--port`` checked in one line, the banner only once the port is
  bound, SIGTERM stops the server with work in flight and leaves no process behind.

Timings are asserted only where the behaviour is a bound by definition, with room for a
loaded machine; ``benchmarks/bench_serve_hostile.py`` measures them.
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
import warnings
import zipfile
import zlib
from pathlib import Path

import numpy as np
import pytest

with warnings.catch_warnings():  # starlette suggests httpx2, a fork; httpx works
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient

import pathfuse
from pathfuse.web.app import create_app, default_map_folders
from pathfuse.web.maps import Limits

BASE = "http://127.0.0.1"
DATA = Path(__file__).parent / "data"
WORLD = DATA / "gazebo" / "known_cells.world"
# DWA with the heaviest tick its bounds allow (64 x 128 x 120 of dwa.TICK_PIECES' 1,000,000
# rollout pieces): tenths of a second per tick, a few hundred ticks on the paper map
SLOW_DWA = {"map": "paper", "planner": "dwa",
            "params": {"v_samples": 64, "w_samples": 128, "horizon_s": 2.4, "sim_step_s": 0.02}}


def _client(**kw):
    return TestClient(create_app(**kw), base_url=BASE)


def _gone(pid: int) -> bool:
    """The process has exited (or is a zombie: it runs no more)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] in ("Z", "X")
    except OSError:
        return True


def _cpu_ticks(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return int(fields[11]) + int(fields[12])
    except OSError:
        return 0


def _wait_for(cond, timeout: float) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.02)
    return cond()


def _register_burn() -> None:
    """``burn``: a plug-in planner that spins the CPU for ``seconds`` and ignores its budget
    (a kernel with no budget check)."""
    from pathfuse.planners.params import Checked
    from pathfuse.validate import param

    @dataclasses.dataclass(frozen=True)
    class Burn(Checked):
        seconds: float = param(30.0, gt=0, le=3600, unit="s", help="how long to spin")

    def burn(grid, start, goal, params, budget):
        end = time.monotonic() + params.seconds
        x = 0
        while time.monotonic() < end:
            x += 1
        return pathfuse.PlanResult(pathfuse.Status.SUCCESS, np.array([start, goal]), 1.0,
                                   planner="burn")

    pathfuse.register_function("burn", burn, Burn, "spins the CPU")


@pytest.fixture(scope="module", autouse=True)
def warm_parent():
    """Compile the kernels a plan uses in this process: workers forked from it have them
    (as ``pathfuse serve`` warms before it forks)."""
    pathfuse.plan(pathfuse.load_map("paper", seed=0), (1, 1), (11, 11), "astar")
    _register_burn()


# --------------------------------------------------------------------------- file reads
_AUDIT: dict = {"on": False, "fd": -1, "installed": False}


def _audit_hook(event, args):
    if not _AUDIT["on"] or event not in ("open", "os.listdir", "os.scandir"):
        return
    p = args[0] if args else None
    if isinstance(p, (str, bytes, os.PathLike)):
        os.write(_AUDIT["fd"], f"{os.getpid()}\t{event}\t{os.fsdecode(p)}\n".encode())


def _secret_files(folder: Path) -> dict[str, Path]:
    """Valid maps of every format a request could name (so a read would change the answer)."""
    from PIL import Image

    folder.mkdir()
    out = {"world": folder / "secret.world", "map": folder / "secret.map",
           "yaml": folder / "secret.yaml", "png": folder / "secret.png",
           "npy": folder / "secret.npy", "pgm": folder / "secret.pgm"}
    out["world"].write_bytes(WORLD.read_bytes())
    out["map"].write_bytes((DATA / "movingai" / "den312d.map").read_bytes())
    Image.fromarray(np.full((4, 4), 255, np.uint8)).save(out["png"])
    Image.fromarray(np.full((4, 4), 255, np.uint8)).save(out["pgm"])
    np.save(out["npy"], np.zeros((4, 4), bool))
    out["yaml"].write_text(f"image: {out['pgm']}\nresolution: 1\norigin: [0, 0, 0]\n"
                           "occupied_thresh: 0.65\nfree_thresh: 0.2\nnegate: 0\n")
    return out


def _zip(name: str, data: bytes) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        z.writestr(name, data)
    return buf.getvalue()


def _hostile_requests(files: dict[str, Path]):
    """(method, url, kwargs) of every way a request can name a file, for these paths."""
    sources = [("gazebo", "world", {}), ("movingai", "map", {}), ("ros", "yaml", {}),
               ("image", "png", {"resolution": 1}), ("npy", "npy", {"resolution": 1}),
               ("world", "world", {}), ("file", "map", {}), ("path", "map", {}),
               ("sdf", "world", {})]
    maps: list = []
    for name in ("world", "map", "yaml", "png"):
        p = str(files[name])
        maps += [p, {"id": p}, {"id": "../../.." + p}, {"paper": p}]
    maps += [{key: str(files[f]), **extra} for key, f, extra in sources]
    maps += [{"gazebo": str(files["world"]), "resolution": 0.05, "bounds": [0, 0, 8, 6]}]
    for m in maps:
        scene = {"map": m, "start": [0.5, 0.5], "goal": [1.5, 0.5]}
        yield "POST", "/api/plan", {"json": {"map": m, "start": [0.5, 0.5], "goal": [1.5, 0.5]}}
        yield "POST", "/api/map", {"json": {"map": m}}
        yield "POST", "/api/field", {"json": {"map": m, "goal": [1, 1]}}
        yield "POST", "/api/simulate", {"json": {"scenario": scene}}
        yield "POST", "/api/scenario/export", {"json": {"scenario": scene}}
    for p in files.values():
        yield "GET", f"/api/maps/{p}", {}
        yield "GET", f"/api/maps/..%2F..%2F..{p}", {}
        yield "GET", f"/api/scenarios/{p}", {}
        for text in (f"map: {p}\n", f"map: {{gazebo: {p}}}\n", f"map: {{movingai: {p}}}\n",
                     f"map: {{ros: {p}}}\n", f"map: {{image: {p}, resolution: 1}}\n"):
            doc = text + "start: [1, 1]\ngoal: [2, 2]\n"
            yield "POST", "/api/scenarios", {"files": {"file": ("s.yaml", doc.encode())}}
    ros = (f"image: {files['pgm']}\nresolution: 1\norigin: [0, 0, 0]\n"
           "occupied_thresh: 0.65\nfree_thresh: 0.2\nnegate: 0\n").encode()
    yield "POST", "/api/maps", {"files": {"file": ("m.yaml", ros)}}
    for member in (str(files["map"]), "../../.." + str(files["map"])):
        yield "POST", "/api/maps", {"files": {"file": ("m.zip", _zip(member, b"x"))}}


def _allowed_roots() -> list[str]:
    roots = [str(Path(pathfuse.__file__).resolve().parent), sys.prefix, sys.base_prefix,
             sys.exec_prefix, "/proc/", "/dev/", "/sys/",
             os.path.join(tempfile.gettempdir(), "pathfuse-upload-"),
             os.path.join(tempfile.gettempdir(), "pathfuse-scenario-")]
    roots += [str(p.resolve()) for _, p in default_map_folders()]
    try:
        import numba

        if numba.config.CACHE_DIR:
            roots.append(str(numba.config.CACHE_DIR))
    except (ImportError, AttributeError):  # pragma: no cover
        pass
    return roots


def test_no_request_reads_a_file_it_names(tmp_path):
    if not _AUDIT["installed"]:
        sys.addaudithook(_audit_hook)  # once per process: audit hooks cannot be removed
        _AUDIT["installed"] = True
    secret = _secret_files(tmp_path / "secret")
    missing = {k: tmp_path / "missing" / p.name for k, p in secret.items()}
    log = tmp_path / "opens.log"
    _AUDIT["fd"] = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
    answers: dict[str, list] = {}
    try:
        _AUDIT["on"] = True  # the workers fork with it on: they log too
        with _client() as c:
            for label, files in (("secret", secret), ("missing", missing)):
                got = answers.setdefault(label, [])
                for method, url, kw in _hostile_requests(files):
                    r = c.request(method, url, **kw)
                    text = r.text
                    for p in files.values():
                        text = text.replace(str(p), "<P>").replace(str(p.parent), "<D>")
                    got.append((method, url.replace(str(files["map"].parent), "<D>"),
                                r.status_code, text))
            assert c.app.state.pool.counters.jobs > 300  # the workers did run them
    finally:
        _AUDIT["on"] = False
        os.close(_AUDIT["fd"])
    a, b = answers["secret"], answers["missing"]
    assert len(a) == len(b) > 150
    for x, y in zip(a, b, strict=True):
        assert x == y  # an existing and a missing path get the same answer
        assert 400 <= x[2] < 500, x
    opened = [line.split("\t") for line in log.read_text().splitlines()]
    assert opened, "the audit hook saw nothing: it is not measuring"
    for _pid, _event, path in opened:  # (an upload is written to a fresh folder, then read)
        assert not path.startswith((str(tmp_path / "secret"), str(tmp_path / "missing"))), path
    # the worker processes open nothing but Python's and pathfuse's files, numba's cache,
    # the shipped maps and the uploads' temporary folders (this process, the server's, is
    # also the test client's: its opens are checked above only)
    roots = _allowed_roots()
    workers = {pid for pid, _, _ in opened if int(pid) != os.getpid()}
    assert workers
    outside = sorted({p for pid, _, p in opened if pid in workers
                      and not any(os.path.abspath(p).startswith(r) for r in roots)})
    assert outside == []


def test_a_gazebo_key_gets_the_answer_of_any_file_key():
    with _client() as c:
        for key in ("gazebo", "movingai", "ros", "image", "npy"):
            r = c.post("/api/plan", json={"map": {key: "/etc/passwd"}, "start": [0, 0],
                                          "goal": [1, 1]})
            assert r.status_code == 400
            assert r.json()["error"] == (f"map.{key}: the server reads no file a request "
                                         "names; upload the map (POST /api/maps) and use its id")
        r = c.post("/api/plan", json={"map": {"colour": 1}, "start": [0, 0], "goal": [1, 1]})
        assert r.status_code == 400 and r.json()["error"].startswith(
            "map.colour: unknown key (a map is one of paper, random, rows, blank, grid, id")


# --------------------------------------------------------------------------- cells, bombs
def _png_header(w: int, h: int) -> bytes:
    def chunk(kind: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(b"")) + chunk(b"IEND", b""))


def _npy_header(shape: tuple[int, int]) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "|b1", "fortran_order": False,
                                               "shape": shape})
    return buf.getvalue()


@pytest.mark.parametrize("name, data, fields, message", [
    ("bomb.png", _png_header(100_000, 100_000), {"resolution": "1"},
     "bomb.png: the image's header claims more pixels than this server's limit"),
    ("big.png", _png_header(3000, 3000), {"resolution": "1"}, "big.png: 3000 x 3000"),
    ("bomb.npy", _npy_header((100_000, 100_000)), {"resolution": "1"},
     "bomb.npy: 100000 x 100000 = 10000000000 cells"),
    ("bomb.zip", _zip("bomb.png", _png_header(100_000, 100_000)), {"resolution": "1"},
     "bomb.png: the image's header claims more pixels"),
])
def test_decompression_bombs_are_413(name, data, fields, message):
    with _client() as c:
        r = c.post("/api/maps", files={"file": (name, data)}, data=fields)
        assert r.status_code == 413 and r.json()["error"].startswith(message), r.json()


def test_gazebo_worlds_are_measured_before_they_are_rasterised(monkeypatch):
    import pathfuse.io.gazebo as gz

    def no_raster(*a, **k):
        raise AssertionError("rasterised")

    world_id = "tests/data/gazebo/known_cells.world"
    with _client(limits=Limits(max_cells=1000)) as c:
        monkeypatch.setattr(gz, "rasterise", no_raster)  # the workers fork with it
        r = c.get(f"/api/maps/{world_id}")  # 0.05 m: 196 x 156 cells
        assert r.status_code == 413, r.json()
        assert r.json()["error"] == (f"{world_id}: 196 x 156 = 30576 cells is more than this "
                                     "server's limit of 1000 cells")
        r = c.post("/api/maps", files={"file": ("w.world", WORLD.read_bytes())},
                   data={"resolution": "0.01"})
        assert r.status_code == 413 and r.json()["error"].startswith("w.world: 980 x 780")
        r = c.post("/api/maps", files={"file": ("w.world.gz", zlib.compress(b"x"))})
        assert r.status_code == 400  # not gzip: the reader says so, nothing rasterised


def test_catalog_maps_within_the_limit_still_load():
    with _client() as c:
        d = c.get("/api/maps/tests/data/gazebo/known_cells.world").json()
        g = pathfuse.load_map(WORLD)
        assert (d["width"], d["height"]) == (g.width, g.height)


# --------------------------------------------------------------------------- parameters
def test_every_planner_parameter_has_bounds():
    from pathfuse.validate import param_spec

    with _client() as c:
        got = c.get("/api/planners").json()
    builtin = [p for p in got
               if pathfuse.get_planner(p["name"]).params_cls.__module__.startswith("pathfuse.")]
    assert len(builtin) >= 12
    for p in builtin:
        spec = pathfuse.get_planner(p["name"])
        for q, f in zip(p["params"], dataclasses.fields(spec.params_cls), strict=True):
            if q["kind"] in ("float", "int"):
                assert q["le"] is not None, (p["name"], q["name"])
                assert q["le"] == param_spec(f).le and "<= " in q["accepts"]
                with pytest.raises(pathfuse.ConfigError, match=f"^{q['name']}: must be"):
                    spec.params_cls(**{q["name"]: q["le"] * 2 + 1})


def test_the_dwa_request_of_the_issue_is_refused_at_once():
    body = {"map": "paper", "planner": "dwa",
            "params": {"v_samples": 250, "w_samples": 250, "horizon_s": 20}, "time_limit": 1}
    with _client() as c:
        t0 = time.monotonic()
        r = c.post("/api/plan", json=body)
        assert r.status_code == 400 and time.monotonic() - t0 < 5
        assert r.json()["error"] == "dwa.v_samples: must be an integer >= 2 and <= 64, got 250"


def test_a_dwa_tick_heavier_than_its_budget_is_refused_at_once():
    # every key within its bound, the product 64 x 128 x 1000 rollout pieces a tick is not
    body = {"map": "paper", "planner": "dwa",
            "params": {"v_samples": 64, "w_samples": 128, "horizon_s": 10, "sim_step_s": 0.01}}
    with _client() as c:
        r = c.post("/api/plan", json=body)
        assert r.status_code == 400
        assert r.json()["error"] == (
            "dwa.v_samples x w_samples x horizon_s / sim_step_s: must be at most 1000000 "
            "rollout pieces a tick, got 64 x 128 x 1000 = 8192000")


def test_planners_lists_the_bounds(capsys):
    from pathfuse.cli import main

    main(["planners", "--params"])
    out = capsys.readouterr().out
    assert "v_samples = 7  (integer >= 2 and <= 64)" in out
    assert "sim_step_s = 0.1 s  (number >= 0.001 and <= 1 s)" in out


# --------------------------------------------------------------------------- workers
def _run_spied(c, body):
    """POST /api/plan, noting the workers that ran it: (response, seconds, worker pids)."""
    pool = c.app.state.pool
    seen: list[int] = []
    done = threading.Event()

    def spy():
        while not done.is_set():
            seen.extend(p for p in pool.busy_pids() if p not in seen)
            time.sleep(0.01)

    t = threading.Thread(target=spy)
    t.start()
    t0 = time.monotonic()
    try:
        r = c.post("/api/plan", json=body)
    finally:
        elapsed = time.monotonic() - t0
        done.set()
        t.join()
    return r, elapsed, seen


def _idle_cpu_ticks(pids: list[int], seconds: float = 0.5) -> int:
    before = {p: _cpu_ticks(p) for p in pids}
    time.sleep(seconds)
    return sum(_cpu_ticks(p) - before[p] for p in pids if not _gone(p))


def test_a_slow_request_is_stopped_at_its_deadline_and_its_cpu_with_it():
    limits = Limits(time_budget_s=1.0, grace_s=0.5)
    with _client(limits=limits) as c:
        pool = c.app.state.pool
        r, elapsed, seen = _run_spied(c, {"map": "paper", "planner": "burn"})
        assert r.status_code == 503
        assert r.json()["error"] == "the request took longer than this server's budget of 1 s"
        assert 1.4 < elapsed < 6.0
        assert len(seen) == 1 and _wait_for(lambda: _gone(seen[0]), 2.0)  # killed
        assert pool.counters.timeouts == 1 and seen[0] not in pool.pids()
        # the next request gets a fresh worker
        assert c.post("/api/plan", json={"map": "paper"}).json()["status"] == "SUCCESS"


def test_a_heavy_dwa_request_ends_within_its_time_and_leaves_no_cpu_running():
    limits = Limits(time_budget_s=1.0, grace_s=0.5)
    with _client(limits=limits) as c:
        r, elapsed, seen = _run_spied(c, SLOW_DWA)
        # killed at the deadline (503), or stopped by the planner's own budget (TIMEOUT)
        assert r.status_code == 503 or r.json()["status"] == "TIMEOUT", r.text
        assert elapsed < 6.0
        assert len(seen) == 1
        assert _wait_for(lambda: _gone(seen[0]), 2.0) or _idle_cpu_ticks(seen) < 10


def test_a_client_that_goes_away_stops_its_computation():
    import anyio

    app = create_app(limits=Limits(time_budget_s=30, grace_s=1))
    pool = app.state.pool
    body = json.dumps({"map": "paper", "planner": "burn"}).encode()
    sent: list[dict] = []

    async def run():
        gone = anyio.Event()
        stage = {"n": 0}

        async def receive():
            stage["n"] += 1
            if stage["n"] == 1:
                return {"type": "http.request", "body": body, "more_body": False}
            await gone.wait()
            return {"type": "http.disconnect"}

        async def send(message):
            sent.append(message)

        scope = {"type": "http", "asgi": {"version": "3.0"}, "http_version": "1.1",
                 "method": "POST", "scheme": "http", "path": "/api/plan", "raw_path":
                 b"/api/plan", "query_string": b"", "root_path": "",
                 "headers": [(b"host", b"127.0.0.1"), (b"content-type", b"application/json"),
                             (b"content-length", str(len(body)).encode())],
                 "client": ("127.0.0.1", 5), "server": ("127.0.0.1", 80)}
        async with anyio.create_task_group() as tg:
            tg.start_soon(app, scope, receive, send)
            with anyio.fail_after(20):
                while not pool.busy_pids():
                    await anyio.sleep(0.01)
            pid = pool.busy_pids()[0]
            await anyio.sleep(0.3)
            t0 = _cpu_ticks(pid)
            assert t0 > 0  # it computes
            gone.set()
        return pid

    pid = anyio.run(run)
    assert _wait_for(lambda: _gone(pid), 2.0)
    assert pool.counters.cancelled == 1
    pool.close()


def test_the_queue_is_bounded_and_the_catalog_stays_served():
    limits = Limits(time_budget_s=6.0, grace_s=0.5)
    with _client(limits=limits, workers=1, max_queue=1) as c:
        pool = c.app.state.pool
        answers: dict[str, object] = {}

        def slow(tag):
            answers[tag] = c.post("/api/plan", json={"map": "paper", "planner": "burn"})

        a = threading.Thread(target=slow, args=("a",))
        a.start()
        assert _wait_for(lambda: pool.busy_pids(), 10)
        b = threading.Thread(target=slow, args=("b",))
        b.start()
        assert _wait_for(lambda: pool.waiting() == 1, 5)
        r = c.post("/api/plan", json={"map": "paper"})
        assert r.status_code == 503 and int(r.headers["retry-after"]) >= 1
        assert r.json()["error"] == ("the server is busy: 1 request is computing and 1 more "
                                     "is waiting")
        # outside the pool: answered while it is full
        for url in ("/", "/static/main.js", "/api/planners", "/api/maps", "/api/scenarios"):
            assert c.get(url).status_code == 200, url
        assert "a" not in answers and pool.busy_pids()  # the slow one still runs
        a.join()
        b.join()
        assert answers["a"].status_code == 503  # its deadline
        assert answers["b"].status_code == 503  # its deadline passed in the queue or running
        assert answers["b"].json()["error"].startswith(("the server is busy",
                                                        "the request took longer"))


def test_a_short_plan_is_answered_while_two_slow_ones_run():
    limits = Limits(time_budget_s=6.0, grace_s=0.5)
    with _client(limits=limits, workers=3) as c:
        pool = c.app.state.pool
        slow_done: list[int] = []

        def slow():
            r = c.post("/api/plan", json={"map": "paper", "planner": "burn"})
            slow_done.append(r.status_code)

        threads = [threading.Thread(target=slow) for _ in range(2)]
        for t in threads:
            t.start()
        assert _wait_for(lambda: len(pool.busy_pids()) == 2, 10)
        short_done = []
        for _ in range(5):
            r = c.post("/api/plan", json={"map": "paper", "planner": "astar"})
            assert r.status_code == 200 and r.json()["status"] == "SUCCESS"
            short_done.append(time.monotonic())
        assert not slow_done  # all five answered while both slow ones ran
        for t in threads:
            t.join()
        assert slow_done == [503, 503]


def test_a_planner_registered_after_the_workers_started_is_known_to_them():
    from pathfuse.planners.params import Checked

    with _client() as c:
        assert c.post("/api/plan", json={"map": "paper"}).status_code == 200

        @dataclasses.dataclass(frozen=True)
        class P(Checked):
            pass

        def straight(grid, start, goal, params, budget):
            return pathfuse.PlanResult(pathfuse.Status.SUCCESS, np.array([start, goal]), 2.0,
                                       planner="late")

        pathfuse.register_function("late", straight, P, "registered late")
        r = c.post("/api/plan", json={"map": "paper", "planner": "late"})
        assert r.status_code == 200 and r.json()["length"] == 2.0


def test_uploads_made_in_a_worker_are_known_to_the_others():
    with _client(workers=2) as c:
        d = c.post("/api/map", json={"map": {"rows": ["..#", "..."]}}).json()
        for _ in range(4):  # whichever worker answers
            r = c.post("/api/plan", json={"map": {"id": d["id"]}, "start": [0.5, 0.5],
                                          "goal": [2.5, 0.5]})
            assert r.json()["status"] == "SUCCESS"
        assert c.get(f"/api/maps/{d['id']}").json()["bits"] == d["bits"]


# --------------------------------------------------------------------------- request rules
@pytest.mark.parametrize("headers, status", [
    ({"content-type": "text/plain"}, 415),
    ({"content-type": "application/x-www-form-urlencoded"}, 415),
    ({"content-type": "multipart/form-data; boundary=x"}, 415),
    ({}, 415),
    ({"content-type": "application/json; charset=latin-1"}, 415),
    ({"content-type": "application/json", "content-encoding": "gzip"}, 415),
    ({"content-type": "application/json; charset=utf-8"}, 200),
    ({"content-type": "Application/JSON"}, 200),
])
def test_bodies_must_be_json(headers, status):
    with _client() as c:
        r = c.post("/api/plan", content=b'{"map": "paper"}', headers=headers)
        assert r.status_code == status, r.text
        if status == 415:
            assert r.json()["error"].startswith("request body: ")


@pytest.mark.parametrize("host, status", [
    ("127.0.0.1", 200), ("localhost:8000", 200), ("LOCALHOST", 200), ("[::1]:8000", 200),
    ("evil.example", 400), ("127.0.0.1.evil.example", 400), ("localhost.evil.example", 400),
    ("", 400),
])
def test_host_allow_list(host, status):
    with _client() as c:
        r = c.get("/api/maps", headers={"host": host})
        assert r.status_code == status
        r = c.post("/api/map", json={"map": "paper"}, headers={"host": host})
        assert r.status_code == status
        if status == 400:
            assert "Host" in r.json()["error"]


def test_allow_host_adds_names():
    with TestClient(create_app(allowed_hosts=["mybox.lan"]), base_url="http://mybox.lan") as c:
        assert c.get("/api/maps").status_code == 200
        assert c.get("/api/maps", headers={"host": "localhost"}).status_code == 400
    with TestClient(create_app(allowed_hosts=["*"]), base_url="http://any.example") as c:
        assert c.get("/api/maps").status_code == 200


@pytest.mark.parametrize("headers, status", [
    ({"origin": "http://127.0.0.1"}, 200),
    ({"origin": "http://evil.example"}, 403),
    ({"origin": "null"}, 403),
    ({"origin": "http://127.0.0.1:9999"}, 403),
    ({"sec-fetch-site": "cross-site", "sec-fetch-mode": "no-cors"}, 403),
    ({"sec-fetch-site": "same-origin", "sec-fetch-mode": "cors"}, 200),
])
def test_origin_check(headers, status):
    with _client() as c:
        r = c.post("/api/map", json={"map": "paper"}, headers=headers)
        assert r.status_code == status, r.text
        r = c.post("/api/maps", files={"file": ("a.map", b"x")}, headers=headers)
        assert (r.status_code == 403) == (status == 403)
    with _client() as c:  # a link from another site still opens the page
        r = c.get("/", headers={"sec-fetch-site": "cross-site", "sec-fetch-mode": "navigate"})
        assert r.status_code == 200


@pytest.mark.parametrize("depth, too_deep", [(5000, True), (100_000, True), (32, True),
                                             (31, False)])
def test_deep_json_is_400(depth, too_deep):
    inner = "[" * depth + "]" * depth  # in an object: depth + 1 levels
    body = f'{{"map": "paper", "layers": {inner}}}'.encode()
    with _client() as c:
        r = c.post("/api/plan", content=body, headers={"content-type": "application/json"})
        assert r.status_code == 400
        if too_deep:
            assert r.json()["error"] == "request body: JSON nested deeper than 32 levels"
        else:  # parsed, then refused by the endpoint
            assert r.json()["error"].startswith("layers: must be a list of")
    with _client() as c:
        r = c.post("/api/plan", content=b'{"map": "paper", "seed": NaN}',
                   headers={"content-type": "application/json"})
        assert r.status_code == 400 and "NaN is not JSON" in r.json()["error"]


# --------------------------------------------------------------------------- command line
def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _serve(*args: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.Popen([sys.executable, "-m", "pathfuse.cli", "serve", *args],
                            stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True,
                            env=env)


@pytest.mark.parametrize("port", ["80000", "-1", "http", "8000.5"])
def test_a_bad_port_is_one_line_and_exit_2(port):
    p = subprocess.run([sys.executable, "-m", "pathfuse.cli", "serve", "--port", port],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr.count("\n") == 1 and "Traceback" not in p.stderr
    assert p.stderr.startswith("pathfuse serve: error: argument --port: must be a port")


def test_a_busy_port_is_one_line_and_no_banner():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        p = subprocess.run([sys.executable, "-m", "pathfuse.cli", "serve", "--port", str(port),
                            "--no-warm"], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and "http://" not in p.stderr and "Traceback" not in p.stderr
    assert p.stderr == (f"pathfuse serve: error: cannot listen on 127.0.0.1:{port}: "
                        "Address already in use\n")


def _children(pid: int) -> list[int]:
    out = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            out += [int(x) for x in (task / "children").read_text().split()]
        except OSError:
            pass
    return out


def _post(port: int, body: dict, timeout: float = 60) -> tuple[int, dict]:
    import urllib.error
    import urllib.request

    req = urllib.request.Request(f"http://127.0.0.1:{port}/api/plan",
                                 data=json.dumps(body).encode(),
                                 headers={"Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as exc:
        return exc.code, json.loads(exc.read())
    except OSError:
        return 0, {}


def test_banner_after_bind_and_sigterm_with_work_in_flight():
    port = _free_port()
    proc = _serve("--port", str(port), "--budget", "30")
    try:
        line = proc.stderr.readline()
        assert line.strip() == f"pathfuse serve: http://127.0.0.1:{port}/  (Ctrl-C stops it)"
        with socket.create_connection(("127.0.0.1", port), timeout=5):
            pass  # the port accepts connections as soon as the banner is out
        answers: list = []
        threads = [threading.Thread(target=lambda: answers.append(_post(port, SLOW_DWA)))
                   for _ in range(2)]
        for t in threads:
            t.start()
        assert _wait_for(lambda: len(_children(proc.pid)) >= 2, 60)
        workers = _children(proc.pid)
        time.sleep(1.0)
        assert not answers  # still computing
        t0 = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        code = proc.wait(timeout=30)
        elapsed = time.monotonic() - t0
        for t in threads:
            t.join(30)
        assert code == 143 and elapsed < 5.0  # the target is 2 s; measured in benchmarks/
        assert proc.stderr.read().strip() == "pathfuse serve: terminated (SIGTERM)"
        assert all(_wait_for(lambda w=w: _gone(w), 2.0) for w in workers)
        assert sorted(a[0] for a in answers) in ([0, 0], [0, 503], [503, 503])
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
