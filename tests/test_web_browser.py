"""The page of ``pathfuse serve`` in a real browser: Debian's chromium driven by Playwright.

CI (``.ci/run``) installs chromium with apt-get, so these tests run there; they are
skipped, saying why, only on a machine with no chromium.  The server is the real
command (``python -m pathfuse.cli serve``) on a free loopback port.

What a user does: load the page, paint an obstacle, drag the goal, run fusion and A*
(both paths drawn, their lengths in the table), toggle the potential layer, place ten
moving discs and play an episode to its end (the frame rate is measured and printed),
upload a malformed map and read the error, and zoom and pan a 1024 x 1024 map.  Then
the page's newer features: a map switch clears the episode state; a drag sends at most
one round of requests, leaves slow planners out while it lasts and cancels stale ones;
discs are checked where they are placed, and move and resize; the planners' colours stay
apart for colour-blind eyes and a click shows one path alone; the results table resizes;
undo, clear, random map, maze and fit; the animated search; the link that restores the
state; the PNG; and the layout at 390 px.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest
from playwright import sync_api  # the test extra installs it (never `playwright install`)

CHROMIUM = next((p for p in (os.environ.get("PATHFUSE_CHROMIUM"), "/usr/bin/chromium",
                             shutil.which("chromium"), shutil.which("chromium-browser")) if p
                 and os.path.exists(p)), None)
if CHROMIUM is None:
    pytest.skip("no chromium on this machine (apt-get install chromium; .ci/run does)",
                allow_module_level=True)

ARGS = ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync",
        "--disable-dev-shm-usage"]
WAIT_MS = 120_000  # a cold numba cache compiles a planner on its first plan


def _wait_until_planners_answer(url, proc):
    """With a cold numba cache the server compiles every planner's kernels in the
    background after it starts, and a worker that gets a plan meanwhile compiles the kernels
    it needs itself; past the 8 s budget it is stopped and the answer is 503 (the first
    plans of a fresh install; docs/guide/playground.md).  The tests here are about the page,
    so they start once an A* and a fusion plan of the page's default map answer."""
    deadline = time.monotonic() + WAIT_MS / 1000.0
    for planner in ("astar", "fusion"):
        body = json.dumps({"map": "paper", "seed": 5, "start": [1, 1], "goal": [11, 11],
                           "planner": planner, "params": {}, "robot_radius": 0.2,
                           "layers": ["closed", "cspace"]}).encode()
        while True:
            req = urllib.request.Request(url + "api/plan", data=body,
                                         headers={"Content-Type": "application/json"})
            try:
                with urllib.request.urlopen(req, timeout=30):
                    break
            except OSError:
                if proc.poll() is not None:
                    raise AssertionError(f"pathfuse serve exited: {proc.stderr.read()}") from None
                if time.monotonic() > deadline:
                    raise AssertionError(
                        f"{planner}: no plan answered within {WAIT_MS} ms") from None
                time.sleep(1.0)


@pytest.fixture(scope="module")
def server():
    # compile (or load) every kernel the server warms into numba's cache first, here: with a
    # cold cache the server's own background warm-up can take longer than a test waits
    from pathfuse.web.app import _warm_all

    class _NoPool:
        def renew(self):
            pass

    _warm_all(_NoPool())
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proc = subprocess.Popen([sys.executable, "-m", "pathfuse.cli", "serve", "--port", str(port)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    url = f"http://127.0.0.1:{port}/"
    try:
        for _ in range(300):
            try:
                with urllib.request.urlopen(url + "api/maps", timeout=2):
                    break
            except OSError:
                if proc.poll() is not None:
                    raise AssertionError(f"pathfuse serve exited: {proc.stderr.read()}") from None
                time.sleep(0.1)
        _wait_until_planners_answer(url, proc)
        yield url
    finally:
        proc.terminate()
        proc.wait(timeout=10)


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


@pytest.fixture
def page(browser, server):
    pg = browser.new_page(viewport={"width": 1400, "height": 900})
    errors: list[str] = []
    pg.on("pageerror", lambda e: errors.append(str(e)))
    pg.goto(server)
    pg.wait_for_selector("body[data-ready]", timeout=WAIT_MS)
    pg.wait_for_selector("body[data-planned]", timeout=WAIT_MS)
    yield pg
    pg.close()
    assert not errors, errors


def frames(pg, n=2):
    pg.evaluate(f"new Promise(r => {{ let k = {n}; const f = () => --k ? "
                "requestAnimationFrame(f) : r(); requestAnimationFrame(f); })")


def replanned(pg, before):
    pg.wait_for_function(f"Number(document.body.dataset.planned) > {before}", timeout=WAIT_MS)
    frames(pg)


def planned(pg):
    return int(pg.evaluate("document.body.dataset.planned"))


def screen(pg, x, y):
    """Page coordinates of world point (x, y)."""
    return pg.evaluate("""([x, y]) => {
        const r = document.getElementById('canvas').getBoundingClientRect();
        const [px, py] = window.pathfuse.view.toScreen(x, y);
        return [r.left + px, r.top + py]; }""", [x, y])


def results(pg):
    return pg.evaluate("Object.fromEntries(window.pathfuse.state.results)")


def table(pg):
    return pg.evaluate("""() => Object.fromEntries([...document.querySelectorAll(
        '#results tbody tr')].map(tr => [tr.dataset.planner,
        [...tr.querySelectorAll('td')].map(td => td.textContent)]))""")


def drawn_share(pg, name):
    """Share of the midpoints of ``name``'s path segments whose canvas pixel has its colour,
    with that path drawn alone (so that another planner's path over it does not count)."""
    return pg.evaluate("""async (name) => {
        const pf = window.pathfuse, c = document.getElementById('canvas');
        const frame = () => new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)));
        pf.state.only = name; pf.view.redraw(); await frame();
        const g = c.getContext('2d'), dpr = window.devicePixelRatio || 1;
        const i = pf.state.forms.findIndex(f => f.name === name);
        const want = getComputedStyle(pf.state.forms[i].box.querySelector('.swatch'))
            .backgroundColor.match(/\\d+/g).map(Number);
        const path = pf.state.results.get(name).path;
        let hit = 0, n = 0;
        for (let k = 1; k < path.length; k++) {
            const x = (path[k-1][0] + path[k][0]) / 2, y = (path[k-1][1] + path[k][1]) / 2;
            const [px, py] = pf.view.toScreen(x, y);
            const d = g.getImageData(Math.round(px * dpr), Math.round(py * dpr), 1, 1).data;
            n++;
            if (Math.hypot(d[0] - want[0], d[1] - want[1], d[2] - want[2]) < 60) hit++;
        }
        pf.state.only = null; pf.view.redraw(); await frame();
        return n ? hit / n : 0; }""", name)


def test_plan_paint_drag_and_the_field(page):
    pg = page
    got = results(pg)
    assert set(got) == {"astar", "fusion"}  # the default choice
    assert got["astar"]["status"] == got["fusion"]["status"] == "SUCCESS"
    rows = table(pg)
    for name in ("astar", "fusion"):
        assert rows[name][3] == f"{got[name]['length']:.3f}"
        assert drawn_share(pg, name) > 0.8, name
    # paint an obstacle on a free cell of A*'s path: A* must go around it
    path = got["astar"]["path"]
    m = pg.evaluate("({w: pathfuse.state.map.width, o: pathfuse.state.map.origin, "
                    "r: pathfuse.state.map.resolution})")
    cell_of = [(round((y - m["o"][1]) / m["r"] - 0.5), round((x - m["o"][0]) / m["r"] - 0.5))
               for x, y in path]
    r, c = cell_of[len(cell_of) // 2]
    x, y = m["o"][0] + (c + 0.5) * m["r"], m["o"][1] + (r + 0.5) * m["r"]
    pg.check("input[name=tool][value=paint]")
    before = planned(pg)
    pg.mouse.click(*screen(pg, x, y))
    assert pg.evaluate(f"pathfuse.state.map.occ[{r} * pathfuse.state.map.width + {c}]") == 1
    replanned(pg, before)
    got2 = results(pg)
    assert got2["astar"]["status"] == "SUCCESS"
    assert (r, c) not in [(round((q[1] - m["o"][1]) / m["r"] - 0.5),
                           round((q[0] - m["o"][0]) / m["r"] - 0.5))
                          for q in got2["astar"]["path"]]
    assert got2["astar"]["length"] >= got["astar"]["length"] - 1e-9
    # drag the goal to another free cell
    pg.check("input[name=tool][value=move]")
    goal = pg.evaluate("pathfuse.state.goal")
    target = (13.0, 3.0)
    assert not pg.evaluate("pathfuse.state.map.occ[3 * 15 + 13]")
    before = planned(pg)
    pg.mouse.move(*screen(pg, *goal))
    pg.mouse.down()
    pg.mouse.move(*screen(pg, 12.0, 6.0), steps=5)
    pg.mouse.move(*screen(pg, *target), steps=5)
    pg.mouse.up()
    replanned(pg, before)
    pg.wait_for_function("(() => { const g = pathfuse.state.results.get('astar').goal;"
                         " return Math.hypot(g[0] - 13, g[1] - 3) < 0.05; })()",
                         timeout=WAIT_MS)
    frames(pg)
    got3 = results(pg)
    for name in ("astar", "fusion"):
        assert got3[name]["status"] == "SUCCESS"
        # the goal where the mouse let go; A* ends at the centre of the goal's cell
        assert math.dist(got3[name]["goal"], target) < 0.05
        assert math.dist(got3[name]["path"][-1], got3[name]["goal"]) <= 0.5 * math.sqrt(2)
        assert drawn_share(pg, name) > 0.8, name
    rows = table(pg)
    assert rows["astar"][3] == f"{got3['astar']['length']:.3f}"
    assert rows["fusion"][3] == f"{got3['fusion']['length']:.3f}"
    assert float(rows["fusion"][7]) >= 0  # min clearance shown
    # the Plan button runs them again with the same answer
    before = planned(pg)
    pg.click("#plan-btn")
    replanned(pg, before)
    assert results(pg)["astar"]["length"] == got3["astar"]["length"]
    # the potential layer: a heat map appears under a free cell, and goes again
    free = pg.evaluate("""(() => { const m = pathfuse.state.map;
        for (let r = 0; r < m.height; r++) for (let c = 0; c < m.width; c++)
          if (!m.occ[r * m.width + c] && r > 8 && c < 4) return [m.origin[0] + c + 0.5,
                                                                m.origin[1] + r + 0.5];
        })()""")

    def pixel():
        frames(pg)
        return pg.evaluate("""([x, y]) => {
            const v = pathfuse.view, dpr = window.devicePixelRatio || 1;
            const [px, py] = v.toScreen(x, y);
            return [...document.getElementById('canvas').getContext('2d')
              .getImageData(Math.round(px * dpr), Math.round(py * dpr), 1, 1).data]; }""", free)

    assert pixel()[:3] == [255, 255, 255]
    pg.check("#layer-heat")
    pg.wait_for_selector("body[data-field]", timeout=WAIT_MS)
    assert pg.evaluate("pathfuse.view.overlays.has('heat')")
    assert pixel()[:3] != [255, 255, 255]
    assert "K_att 40" in pg.inner_text("#field-info")
    pg.uncheck("#layer-heat")
    assert pixel()[:3] == [255, 255, 255]


def test_ten_discs_play_an_episode_to_its_end(page, tmp_path):
    pg = page
    pg.fill("#blank-w", "40")
    pg.fill("#blank-h", "30")
    pg.fill("#blank-res", "0.5")
    before = planned(pg)
    pg.click("#blank-make")
    pg.wait_for_function("pathfuse.state.map.width === 40")
    replanned(pg, before)  # the new map is planned at once (it is small)
    assert pg.evaluate("pathfuse.state.start") == [0.25, 0.25]
    pg.check("input[name=tool][value=disc]")
    for k in range(10):  # press at the centre, drag the velocity
        x, y = 3.0 + 1.5 * k, 6.0 + (k % 3) * 3.0
        pg.mouse.move(*screen(pg, x, y))
        pg.mouse.down()
        pg.mouse.move(*screen(pg, x - 0.3, y + 0.5), steps=3)
        pg.mouse.up()
    discs = pg.evaluate("pathfuse.scene.obstacles")
    assert len(discs) == 10 and pg.locator("#discs .disc").count() == 10
    assert discs[0]["position"] == pytest.approx([3.0, 6.0], abs=0.05)
    assert discs[0]["velocity"] == pytest.approx([-0.3, 0.5], abs=0.05)
    pg.select_option("#sim-planner", "fusion")
    pg.fill("#sim-limit", "40")
    pg.click("#sim-run")
    pg.wait_for_selector("body[data-episode]", timeout=WAIT_MS)
    pg.wait_for_selector("body[data-playback=ended]", timeout=WAIT_MS)
    ep = pg.evaluate("(() => { const e = pathfuse.player.ep; return {n: e.n_ticks, "
                     "status: e.status, discs: e.obstacle_radii.length}; })()")
    assert ep["discs"] == 10
    assert pg.evaluate("pathfuse.player.tick") == ep["n"]
    assert int(pg.evaluate("document.getElementById('time').value")) == ep["n"]
    outcome = pg.inner_text("#outcome")
    assert outcome.startswith(f"fusion: {ep['status']}")
    stats = pg.evaluate("pathfuse.player.stats")
    assert stats["discs"] == 10 and stats["frames"] > 10
    print(f"\nplayback of {ep['n']} ticks with 10 discs: {stats['fps']:.1f} frames/s, "
          f"median frame {stats['median_frame_ms']:.1f} ms, 95th percentile "
          f"{stats['p95_frame_ms']:.1f} ms, longest {stats['max_frame_ms']:.1f} ms")
    out = os.environ.get("PATHFUSE_FPS_OUT")
    if out:
        Path(out).write_text(json.dumps(stats))
    # the time slider seeks
    pg.locator("#time").fill("5")
    assert pg.evaluate("pathfuse.player.tick") == 5
    # export the scene: pathfuse simulate runs it unchanged, with the same outcome
    with pg.expect_download() as dl:
        pg.click("#sim-export")
    path = tmp_path / "scene.yaml"
    dl.value.save_as(path)
    assert pg.inner_text("#export-yaml").strip() == path.read_text().strip()
    run = subprocess.run([sys.executable, "-m", "pathfuse.cli", "simulate", str(path),
                          "--json"], capture_output=True, text=True, timeout=300)
    assert json.loads(run.stdout)["status"] == ep["status"]
    assert json.loads(run.stdout)["n_ticks"] == ep["n"]


def test_a_malformed_map_upload_shows_the_error(page, tmp_path):
    pg = page
    bad = tmp_path / "broken.map"
    bad.write_text("type octile\nheight 3\nwidth many\nmap\n...\n")
    pg.set_input_files("#map-file", str(bad))
    pg.wait_for_function("document.getElementById('map-error').textContent.length > 0")
    msg = pg.inner_text("#map-error")
    assert msg.startswith("broken.map") and "width" in msg
    assert pg.evaluate("pathfuse.state.map.name") == "paper-5"  # the map is kept
    good = Path(__file__).parent / "data" / "movingai" / "maze-32-32-2.map"
    pg.set_input_files("#map-file", str(good))
    pg.wait_for_function("pathfuse.state.map.name === 'maze-32-32-2'")
    assert pg.inner_text("#map-error") == ""


def test_a_1024_map_zooms_pans_and_paints(page):
    pg = page
    pg.fill("#blank-w", "1024")
    pg.fill("#blank-h", "1024")
    pg.fill("#blank-res", "1")
    pg.click("#blank-make")
    pg.wait_for_function("pathfuse.state.map.width === 1024")
    frames(pg)
    scale = pg.evaluate("pathfuse.view.scale")
    cx, cy = screen(pg, 512, 512)
    t0 = time.perf_counter()
    for _ in range(10):
        pg.mouse.move(cx, cy)
        pg.mouse.wheel(0, -300)
    frames(pg)
    assert pg.evaluate("pathfuse.view.scale") > 4 * scale
    x0 = pg.evaluate("pathfuse.view.cx")
    pg.mouse.move(cx, cy)
    pg.mouse.down(button="right")
    pg.mouse.move(cx - 200, cy, steps=10)
    pg.mouse.up(button="right")
    assert pg.evaluate("pathfuse.view.cx") > x0
    pg.check("input[name=tool][value=paint]")
    pg.fill("#brush", "5")
    before = planned(pg)
    pg.mouse.move(cx, cy + 100)
    pg.mouse.down()
    pg.mouse.move(cx + 150, cy + 100, steps=15)
    pg.mouse.up()
    frames(pg)
    painted = pg.evaluate("pathfuse.state.map.occ.reduce((a, b) => a + b, 0)")
    assert painted > 25 and pg.evaluate("pathfuse.state.map.dirty")
    elapsed = time.perf_counter() - t0
    print(f"\n1024 x 1024 map: 10 zoom steps, a pan and a painted stroke in {elapsed:.2f} s")
    # a map this big is planned on request, not on every edit
    assert planned(pg) == before
    pg.click("#plan-btn")
    replanned(pg, before)
    got = results(pg)
    assert got["astar"]["status"] == "SUCCESS"


# ---------------------------------------------------------------------------- the new page

def select_map(pg, map_id, name):
    before = planned(pg)
    pg.select_option("#map-select", map_id)
    pg.wait_for_function(f"pathfuse.state.map && pathfuse.state.map.name === {json.dumps(name)}",
                         timeout=WAIT_MS)
    return before


def free_centre(pg, clear=1, far_from=None, min_dist=0.0, skip=0):
    """World centre of a free cell whose (2 clear + 1)^2 block is free, at least ``min_dist``
    from ``far_from``; the ``skip``-th such cell in row-major order."""
    return pg.evaluate("""([k, far, dmin, skip]) => { const m = pathfuse.state.map;
        let n = 0;
        for (let r = k; r < m.height - k; r++) for (let c = k; c < m.width - k; c++) {
          let ok = true;
          for (let i = -k; i <= k && ok; i++) for (let j = -k; j <= k; j++)
            if (m.occ[(r + i) * m.width + c + j]) { ok = false; break; }
          if (!ok) continue;
          const x = m.origin[0] + (c + 0.5) * m.resolution;
          const y = m.origin[1] + (r + 0.5) * m.resolution;
          if (far && Math.hypot(x - far[0], y - far[1]) < dmin) continue;
          if (n++ === skip) return [x, y];
        }
        return null; }""", [clear, far_from, min_dist, skip])


def free_near(pg, x, y):
    """The centre of the free cell nearest to (x, y) whose 3 x 3 block is free."""
    return pg.evaluate("""([x, y]) => { const m = pathfuse.state.map; let best = null, bd = 1e18;
        for (let r = 1; r < m.height - 1; r++) for (let c = 1; c < m.width - 1; c++) {
          let ok = true;
          for (let i = -1; i <= 1 && ok; i++) for (let j = -1; j <= 1; j++)
            if (m.occ[(r + i) * m.width + c + j]) { ok = false; break; }
          if (!ok) continue;
          const px = m.origin[0] + (c + 0.5) * m.resolution;
          const py = m.origin[1] + (r + 0.5) * m.resolution;
          const d = (px - x) ** 2 + (py - y) ** 2;
          if (d < bd) { bd = d; best = [px, py]; }
        }
        return best; }""", [x, y])


def place_disc(pg, x, y, vx=0.3, vy=0.0):
    pg.check("input[name=tool][value=disc]")
    pg.mouse.move(*screen(pg, x, y))
    pg.mouse.down()
    pg.mouse.move(*screen(pg, x + vx, y + vy), steps=3)
    pg.mouse.up()


def test_switching_maps_clears_the_episode_state(page, tmp_path):
    pg = page
    start = pg.evaluate("pathfuse.state.start")
    for k in range(2):
        place_disc(pg, *free_centre(pg, far_from=start, min_dist=3, skip=5 * k))
    assert pg.evaluate("pathfuse.scene.obstacles.length") == 2
    pg.fill("#sim-limit", "5")
    pg.click("#sim-run")
    pg.wait_for_selector("body[data-episode]", timeout=WAIT_MS)
    with pg.expect_download():
        pg.click("#sim-export")
    pg.wait_for_function("document.getElementById('export-yaml').textContent.length > 0")
    assert pg.inner_text("#outcome").startswith("fusion: ")
    assert pg.evaluate("pathfuse.player.ep !== null")
    select_map(pg, "tests/data/movingai/maze-32-32-2.map", "maze-32-32-2")
    assert pg.evaluate("pathfuse.scene.obstacles") == []
    assert pg.locator("#discs .disc").count() == 0
    assert pg.evaluate("pathfuse.player.ep") is None
    assert pg.evaluate("document.getElementById('outcome').textContent") == ""
    assert pg.evaluate("document.getElementById('export-yaml').textContent") == ""
    assert not pg.evaluate("document.getElementById('export-box').open")
    assert pg.evaluate("document.body.dataset.episode") is None
    assert pg.is_disabled("#time") and pg.is_disabled("#play")
    # undo brings the old map back, with its discs
    pg.click("#undo")
    pg.wait_for_function("pathfuse.state.map.name === 'paper-5'")
    assert pg.evaluate("pathfuse.scene.obstacles.length") == 2


def test_a_drag_sends_one_round_leaves_slow_planners_out_and_cancels_stale_ones(page):
    pg = page
    select_map(pg, "tests/data/movingai/Boston_0_256.map", "Boston_0_256")
    before = planned(pg)
    pg.check("input[data-planner=dwa]")  # the slow one (seconds on this map)
    replanned(pg, before)
    pg.wait_for_function("(() => { const r = pathfuse.state.results.get('dwa');"
                         " return r && !r.stale; })()", timeout=WAIT_MS)
    assert pg.evaluate("pathfuse.state.took.get('dwa')") > 300
    sent, failed = [], []

    def on_request(req):
        if req.url.endswith("/api/plan") and req.method == "POST":
            sent.append(json.loads(req.post_data))

    pg.on("request", on_request)
    pg.on("requestfailed", lambda req: failed.append((json.loads(req.post_data)["planner"],
                                                      req.failure))
          if req.url.endswith("/api/plan") else None)
    goal = pg.evaluate("pathfuse.state.goal")
    targets = [free_near(pg, x, y) for x, y in ((150, 150), (120, 180), (180, 120))]
    pg.evaluate("window.__moves = []; document.getElementById('canvas').addEventListener("
                "'pointermove', (e) => { if (e.buttons) __moves.push(performance.now()); })")

    def drag(src, dst, n=40, hesitate=(), rest=None):
        a, b = screen(pg, *src), screen(pg, *dst)
        pg.mouse.move(*a)
        pg.mouse.down()
        for i in range(1, n + 1):
            t = i / n
            pg.mouse.move(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))
            time.sleep(0.016)  # about 60 moves a second, as a mouse sends them
            if i in hesitate:
                time.sleep(0.12)  # a hand that hesitates, shorter than the rest that re-plans
            if rest and i == rest[0]:
                rest[1]()
        pg.mouse.up()

    # 1. a drag with hesitations: one round of the three planners, when the mouse is let go
    before = planned(pg)
    drag(goal, targets[0], hesitate=(10, 20, 30))
    replanned(pg, before)
    pg.wait_for_function("[...pathfuse.state.results.values()].every(r => !r.stale)",
                         timeout=WAIT_MS)
    gaps = pg.evaluate("__moves.slice(1).map((t, i) => t - __moves[i])")
    rests = sum(g >= 200 for g in gaps)  # a stalled machine can make a rest of its own
    print(f"\ndrag 1: {len(sent)} plan requests for {len(gaps) + 1} pointer moves "
          f"(longest gap {max(gaps):.0f} ms)")
    assert len(sent) <= 3 + 2 * rests
    assert sorted(r["planner"] for r in sent[-3:]) == ["astar", "dwa", "fusion"]
    assert all(r["goal"] == pytest.approx(targets[0], abs=0.05) for r in sent[-3:])
    assert not failed
    # 2. a drag that rests: the fast planners re-plan during the rest, DWA only at the end
    sent.clear()

    during = {}

    def resting():
        # which planners count as slow is decided from how long each last answer took (more
        # than 300 ms: wait for the release); on a loaded machine fusion can be one of them
        during["took"] = pg.evaluate("Object.fromEntries(pathfuse.state.took)")
        n0 = planned(pg)
        pg.wait_for_function(f"Number(document.body.dataset.planned) > {n0}", timeout=WAIT_MS)
        during["sent"] = [r["planner"] for r in sent]
        during["rows"] = table(pg)

    drag(targets[0], targets[1], n=20, rest=(10, resting))
    pg.wait_for_function("[...pathfuse.state.results.values()].every(r => !r.stale)",
                         timeout=WAIT_MS)
    fast = sorted(p for p in ("astar", "fusion") if during["took"][p] <= 300)
    assert during["took"]["dwa"] > 300 and "astar" in fast
    assert sorted(during["sent"]) == fast
    assert "when you let go" in during["rows"]["dwa"][2]
    assert "dwa" in [r["planner"] for r in sent[2:]]
    # 3. Plan, then a drag at once: the requests of the Plan round are cancelled
    sent.clear()
    pg.click("#plan-btn")
    while len(sent) < 3:
        pg.wait_for_timeout(20)
    pg.wait_for_timeout(400)  # astar and fusion have answered, DWA is computing
    before = planned(pg)
    drag(targets[1], targets[2], n=10)
    replanned(pg, before)
    pg.wait_for_function("[...pathfuse.state.results.values()].every(r => !r.stale)",
                         timeout=WAIT_MS)
    assert ("dwa", "net::ERR_ABORTED") in failed
    got = results(pg)
    for name in ("astar", "fusion", "dwa"):
        assert got[name]["goal"] == pytest.approx(targets[2], abs=0.05), name


def overlay_cells(pg):
    """The cells of the animated search's overlay by colour: {closed: [...], open: [...]}
    (row-major cell indices; the overlay canvas has one pixel per cell, top row first)."""
    return pg.evaluate("""() => { const a = pathfuse.search.anim, W = a.W, H = a.H;
        const d = a.canvas.getContext('2d').getImageData(0, 0, W, H).data;
        const out = {closed: [], open: []};
        for (let i = 0; i < H; i++) for (let j = 0; j < W; j++) {
          const o = (i * W + j) * 4, cell = (H - 1 - i) * W + j;
          if (d[o + 3] === 120) out.closed.push(cell); else if (d[o + 3]) out.open.push(cell);
        }
        return out; }""")


def test_the_search_animation_plays_in_expansion_order(page):
    pg = page
    pg.fill("#search-speed", "18")  # about 20 expansions a second
    assert 15 <= pg.evaluate("Math.round(10 ** (0.5 + 4.5 * 18 / 100))") <= 25
    pg.select_option("#search-planner", "astar")
    pg.click("#search-start")
    pg.wait_for_selector("body[data-search=playing]", timeout=WAIT_MS)
    n = pg.evaluate("pathfuse.search.n")
    assert n == results(pg)["astar"]["expansions"] > 20
    order = pg.evaluate("[...pathfuse.search.anim.order]")
    m = pg.evaluate("({w: pathfuse.state.map.width, occ: [...pathfuse.state.map.occ]})")
    w = m["w"]
    start = pg.evaluate("pathfuse.state.start")
    assert order[0] == int(start[1]) * w + int(start[0])  # the start is expanded first
    goal = results(pg)["astar"]["path"][-1]
    assert order[-1] == int(goal[1]) * w + int(goal[0])  # and the goal last
    pg.wait_for_function("pathfuse.search.k >= 3", timeout=WAIT_MS)
    k1 = pg.evaluate("pathfuse.search.k")
    pg.wait_for_timeout(500)
    k2 = pg.evaluate("pathfuse.search.k")
    assert 0 < k1 < k2 < n  # it grows while it plays
    # pause: it stops growing; what is drawn is the first k cells of the order, and the
    # open set is their free neighbours
    pg.click("#search-play")
    pg.wait_for_selector("body[data-search=paused]")
    k = pg.evaluate("pathfuse.search.k")
    pg.wait_for_timeout(400)
    assert pg.evaluate("pathfuse.search.k") == k
    cells = overlay_cells(pg)
    assert sorted(cells["closed"]) == sorted(order[:k])
    assert cells["open"] and not set(cells["open"]) & set(order[:k])
    for c in cells["open"]:
        r, col = divmod(c, w)
        assert not m["occ"][c]
        assert any((r + dr) * w + col + dc in set(order[:k])
                   for dr in (-1, 0, 1) for dc in (-1, 0, 1))
    # scrub back, then play to the end: every expanded cell, then the path
    pg.fill("#search-step", "5")
    assert pg.evaluate("pathfuse.search.k") == 5
    assert sorted(overlay_cells(pg)["closed"]) == sorted(order[:5])
    pg.fill("#search-speed", "100")
    pg.click("#search-play")
    pg.wait_for_selector("body[data-search=done]", timeout=WAIT_MS)
    assert pg.evaluate("pathfuse.search.k") == n
    assert sorted(overlay_cells(pg)["closed"]) == sorted(order)
    frames(pg)
    path = results(pg)["astar"]["path"]
    mid = [(path[3][0] + path[4][0]) / 2, (path[3][1] + path[4][1]) / 2]
    px = pg.evaluate("""([x, y]) => { const v = pathfuse.view, dpr = window.devicePixelRatio || 1;
        const [px, py] = v.toScreen(x, y);
        return [...document.getElementById('canvas').getContext('2d')
          .getImageData(Math.round(px * dpr), Math.round(py * dpr), 1, 1).data]; }""", mid)
    assert px[:3] == [0x00, 0x56, 0x8F]  # astar's colour: the path is drawn at the end
    # closing it brings the planners' paths back
    pg.click("#search-close")
    assert pg.evaluate("pathfuse.view.overlays.has('search')") is False
    assert pg.evaluate("document.body.dataset.search") is None
    assert drawn_share(pg, "fusion") > 0.8


def test_the_link_restores_the_state(page, browser):
    pg = page
    pg.fill("#map-seed", "7")
    before = planned(pg)
    pg.click("#map-load")
    pg.wait_for_function("pathfuse.state.map.name === 'paper-7'")
    replanned(pg, before)
    # paint a wall, move the goal, change the radius, tick thetastar, change a parameter,
    # place a disc and show fusion alone
    start = pg.evaluate("pathfuse.state.start")
    wall = free_centre(pg, clear=0, far_from=start, min_dist=4, skip=30)
    pg.check("input[name=tool][value=paint]")
    pg.mouse.click(*screen(pg, *wall))
    goal = pg.evaluate("pathfuse.state.goal")
    target = free_centre(pg, clear=0, far_from=start, min_dist=8, skip=3)
    pg.check("input[name=tool][value=move]")
    pg.mouse.move(*screen(pg, *goal))
    pg.mouse.down()
    pg.mouse.move(*screen(pg, *target), steps=4)
    pg.mouse.up()
    pg.fill("#robot-radius", "0.3")
    pg.press("#robot-radius", "Tab")
    pg.check("input[data-planner=thetastar]")
    fusion = pg.locator(".planner", has=pg.locator("input[data-planner=fusion]"))
    fusion.locator("summary").click()
    pg.fill("input[name='fusion.k_att']", "30")
    pg.press("input[name='fusion.k_att']", "Tab")
    place_disc(pg, *free_centre(pg, far_from=start, min_dist=3, skip=2), vx=-0.4, vy=0.2)
    pg.wait_for_function("[...pathfuse.state.results.values()].every(r => !r.stale) && "
                         "pathfuse.state.results.size === 3", timeout=WAIT_MS)
    pg.click("#results tbody tr[data-planner=fusion]")
    pg.wait_for_timeout(700)  # the address is written 0.3 s after the last change
    url = pg.evaluate("location.href")
    assert "#z=" in url
    print(f"\nthe link is {len(url)} characters long")

    def snap(p):
        return p.evaluate("""() => { const s = pathfuse.state, m = s.map;
            return {name: m.name, size: [m.width, m.height, m.resolution], occ: [...m.occ],
                    start: s.start, goal: s.goal,
                    radius: document.getElementById('robot-radius').value,
                    ticked: s.forms.filter(f => f.check.checked).map(f => f.name),
                    params: Object.fromEntries(s.forms.filter(f => f.check.checked)
                      .map(f => [f.name, f.params()])),
                    discs: pathfuse.scene.obstacles, only: s.only,
                    lengths: Object.fromEntries([...s.results].map(([k, r]) => [k, r.length]))};
            }""")

    want = snap(pg)
    assert want["radius"] == "0.3" and want["only"] == "fusion"
    assert want["params"]["fusion"] == {"k_att": 30} and len(want["discs"]) == 1
    assert sorted(want["ticked"]) == ["astar", "fusion", "thetastar"]
    assert want["goal"] == pytest.approx(target, abs=0.05)
    other = browser.new_page(viewport={"width": 1000, "height": 800})
    try:
        other.goto(url)
        other.wait_for_selector("body[data-restored]", timeout=WAIT_MS)
        other.wait_for_selector("body[data-planned]", timeout=WAIT_MS)
        other.wait_for_function("pathfuse.state.results.size === 3 && "
                                "[...pathfuse.state.results.values()].every(r => !r.stale)",
                                timeout=WAIT_MS)
        got = snap(other)
        assert got == want
        assert other.evaluate("document.querySelector('#results tr.isolated').dataset.planner"
                              ) == "fusion"
    finally:
        other.close()


def test_discs_are_checked_where_they_are_placed_and_move_and_resize(page):
    pg = page
    start = pg.evaluate("pathfuse.state.start")
    wall = pg.evaluate("""(() => { const m = pathfuse.state.map;
        for (let r = 3; r < m.height; r++) for (let c = 3; c < m.width; c++)
          if (m.occ[r * m.width + c]) return [c + 0.5, r + 0.5]; })()""")
    # on a wall: refused at once, with the reason the server gives at Run
    place_disc(pg, *wall)
    assert pg.evaluate("pathfuse.scene.obstacles.length") == 0
    assert "overlaps an occupied cell or the map's edge" in pg.inner_text("#sim-error")
    # on the robot at the start: refused too
    place_disc(pg, start[0] + 0.7, start[1])
    assert pg.evaluate("pathfuse.scene.obstacles.length") == 0
    assert "overlaps the robot at the start" in pg.inner_text("#sim-error")
    # a free spot: placed (radius 0.6 m on a 1 m map)
    a = free_centre(pg, far_from=start, min_dist=3, skip=0)
    b = free_centre(pg, far_from=a, min_dist=3, skip=4)
    place_disc(pg, *a, vx=0.5, vy=0.0)
    assert pg.inner_text("#sim-error") == ""
    disc = pg.evaluate("pathfuse.scene.obstacles[0]")
    assert disc["position"] == pytest.approx(a, abs=0.05) and disc["radius"] == 0.6

    def drag(src, dst):
        pg.mouse.move(*screen(pg, *src))
        pg.mouse.down()
        pg.mouse.move(*screen(pg, *dst), steps=5)
        pg.mouse.up()

    # move it (press inside, off the centre)
    drag((a[0] - 0.2, a[1] + 0.1), (b[0] - 0.2, b[1] + 0.1))
    disc = pg.evaluate("pathfuse.scene.obstacles[0]")
    assert disc["position"] == pytest.approx(b, abs=0.05)
    # resize it by its rim (its 3 x 3 block is free: up to 1 m fits)
    drag((b[0], b[1] - 0.6), (b[0], b[1] - 0.9))
    assert pg.evaluate("pathfuse.scene.obstacles[0].radius") == pytest.approx(0.9, abs=0.05)
    # change its velocity by its arrow's head
    drag((b[0] + 0.5, b[1]), (b[0] + 0.3, b[1] + 0.6))
    assert pg.evaluate("pathfuse.scene.obstacles[0].velocity") == pytest.approx([0.3, 0.6],
                                                                               abs=0.05)
    # moved onto a wall: refused, it stays where it was
    drag(b, wall)
    assert pg.evaluate("pathfuse.scene.obstacles[0].position") == pytest.approx(b, abs=0.05)
    assert "overlaps an occupied cell" in pg.inner_text("#sim-error")
    # the radius in the list
    inp = pg.locator("#discs .disc input").first
    inp.fill("0.7")
    inp.press("Tab")
    assert pg.evaluate("pathfuse.scene.obstacles[0].radius") == 0.7
    # a wall painted under it later: the list says why it cannot be there
    pg.check("input[name=tool][value=paint]")
    pg.mouse.click(*screen(pg, b[0] + 1.0, b[1]))
    assert "overlaps an occupied cell" in pg.inner_text("#discs")
    # undo: the wall goes, then the radius comes back
    pg.click("#undo")
    assert pg.inner_text("#discs").count("overlaps") == 0
    pg.click("#undo")
    assert pg.evaluate("pathfuse.scene.obstacles[0].radius") == pytest.approx(0.9, abs=0.05)


# Machado, Oliveira and Fernandes (2009), severity 1: linear-RGB matrices simulating
# protanopia, deuteranopia and tritanopia
CVD = {
    "normal": ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
    "protan": ((0.152286, 1.052583, -0.204868), (0.114503, 0.786281, 0.099216),
               (-0.003882, -0.048116, 1.051998)),
    "deutan": ((0.367322, 0.860646, -0.227968), (0.280085, 0.672501, 0.047413),
               (-0.011820, 0.042940, 0.968881)),
    "tritan": ((1.255528, -0.076749, -0.178779), (-0.078411, 0.930809, 0.147602),
               (0.004733, 0.691367, 0.303900)),
}


def _linear(rgb):
    return [c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4
            for c in (v / 255 for v in rgb)]


def _lab(lin):
    xyz = [sum(k * v for k, v in zip(row, lin, strict=True)) for row in
           ((0.4124564, 0.3575761, 0.1804375), (0.2126729, 0.7151522, 0.0721750),
            (0.0193339, 0.1191920, 0.9503041))]
    f = [t ** (1 / 3) if t > (6 / 29) ** 3 else t / (3 * (6 / 29) ** 2) + 4 / 29
         for t in (a / b for a, b in zip(xyz, (0.95047, 1.0, 1.08883), strict=True))]
    return 116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])


def _de2000(p, q):
    """CIEDE2000 colour difference of two CIELAB colours."""
    (l1, a1, b1), (l2, a2, b2) = p, q
    cb = (math.hypot(a1, b1) + math.hypot(a2, b2)) / 2
    g = 0.5 * (1 - math.sqrt(cb ** 7 / (cb ** 7 + 25 ** 7)))
    a1p, a2p = (1 + g) * a1, (1 + g) * a2
    c1, c2 = math.hypot(a1p, b1), math.hypot(a2p, b2)
    h1, h2 = math.degrees(math.atan2(b1, a1p)) % 360, math.degrees(math.atan2(b2, a2p)) % 360
    dh = 0 if c1 * c2 == 0 else h2 - h1 - 360 if h2 - h1 > 180 else \
        h2 - h1 + 360 if h2 - h1 < -180 else h2 - h1
    d_h = 2 * math.sqrt(c1 * c2) * math.sin(math.radians(dh / 2))
    lm, cm = (l1 + l2) / 2, (c1 + c2) / 2
    hm = h1 + h2 if c1 * c2 == 0 else (h1 + h2) / 2 if abs(h1 - h2) <= 180 else \
        (h1 + h2 + 360) / 2 if h1 + h2 < 360 else (h1 + h2 - 360) / 2
    t = (1 - 0.17 * math.cos(math.radians(hm - 30)) + 0.24 * math.cos(math.radians(2 * hm))
         + 0.32 * math.cos(math.radians(3 * hm + 6)) - 0.20 * math.cos(math.radians(4 * hm - 63)))
    rt = -math.sin(math.radians(60 * math.exp(-(((hm - 275) / 25) ** 2)))) * \
        2 * math.sqrt(cm ** 7 / (cm ** 7 + 25 ** 7))
    sl = 1 + 0.015 * (lm - 50) ** 2 / math.sqrt(20 + (lm - 50) ** 2)
    sc, sh = 1 + 0.045 * cm, 1 + 0.015 * cm * t
    dl, dc, dhh = (l2 - l1) / sl, (c2 - c1) / sc, d_h / sh
    return math.sqrt(dl * dl + dc * dc + dhh * dhh + rt * dc * dhh)


def test_de2000_matches_published_pairs():
    # Sharma, Wu and Dalal (2005), the CIEDE2000 test data: pairs 1, 7 and 17
    assert _de2000((50, 2.6772, -79.7751), (50, 0, -82.7485)) == pytest.approx(2.0425, abs=1e-4)
    assert _de2000((50, 0, 0), (50, -1, 2)) == pytest.approx(2.3669, abs=1e-4)
    assert _de2000((50, 2.5, 0), (73, 25, -18)) == pytest.approx(27.1492, abs=1e-4)


def test_each_planner_has_a_colour_apart_for_colour_blind_eyes_and_a_click_isolates(page):
    pg = page
    cols = pg.evaluate("""pathfuse.state.forms.map(f => [f.name, getComputedStyle(
        f.box.querySelector('.swatch')).backgroundColor.match(/\\d+/g).map(Number)])""")
    assert len(cols) >= 12 and len({tuple(c) for _, c in cols}) == len(cols)
    worst = {}
    for kind, mat in CVD.items():
        labs = [_lab([max(0.0, min(1.0, sum(k * v for k, v in zip(row, _linear(c), strict=True))))
                      for row in mat]) for _, c in cols]
        worst[kind] = min(_de2000(labs[i], labs[j]) for i in range(len(labs))
                          for j in range(i + 1, len(labs)))
    print("\nleast CIEDE2000 between two planners' colours: "
          + ", ".join(f"{k} {v:.1f}" for k, v in worst.items()))
    assert min(worst.values()) >= 12
    for _, c in cols:  # visible on the white map
        y = sum(k * v for k, v in zip((0.2126, 0.7152, 0.0722), _linear(c),
                                      strict=True))
        assert 1.05 / (y + 0.05) >= 2.2
    # click a row: that path alone; click it again: all
    pg.click("#results tbody tr[data-planner=astar]")
    assert pg.evaluate("pathfuse.state.only") == "astar"
    assert pg.locator("#results tr.dimmed").count() == 1
    frames(pg)
    fus = results(pg)["fusion"]["path"]
    ast = results(pg)["astar"]["path"]
    def to_segment(p, a, b):
        ab = (b[0] - a[0], b[1] - a[1])
        t = max(0.0, min(1.0, ((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1])
                         / ((ab[0] ** 2 + ab[1] ** 2) or 1)))
        return math.dist(p, (a[0] + t * ab[0], a[1] + t * ab[1]))

    # a point of fusion's path at least 10 pixels from astar's
    dmin = 10 / pg.evaluate("pathfuse.view.scale")
    far = next(p for p in fus
               if min(to_segment(p, ast[k - 1], ast[k]) for k in range(1, len(ast))) > dmin)

    def colour_at(p):
        frames(pg)
        return pg.evaluate("""([x, y]) => { const dpr = window.devicePixelRatio || 1;
            const [px, py] = pathfuse.view.toScreen(x, y);
            return [...document.getElementById('canvas').getContext('2d')
              .getImageData(Math.round(px * dpr), Math.round(py * dpr), 1, 1).data].slice(0, 3);
            }""", p)

    fusion_rgb = dict(cols)["fusion"]

    def is_fusion(rgb):
        return math.dist(rgb, fusion_rgb) < 40

    assert not is_fusion(colour_at(far))  # hidden while astar is alone
    pg.click("#results tbody tr[data-planner=astar]")
    assert pg.evaluate("pathfuse.state.only") is None
    assert is_fusion(colour_at(far))
    # click on fusion's path in the map: fusion alone; click empty space: all again
    pg.mouse.click(*screen(pg, *far))
    assert pg.evaluate("pathfuse.state.only") == "fusion"
    pg.mouse.click(*screen(pg, -0.5, -0.5))
    assert pg.evaluate("pathfuse.state.only") is None


def test_the_results_table_resizes(page):
    pg = page
    pg.set_viewport_size({"width": 1400, "height": 700})
    names = pg.evaluate("pathfuse.state.forms.map(f => f.name)")
    for name in names:
        pg.check(f"input[data-planner={name}]")
    pg.wait_for_function(f"pathfuse.state.results.size === {len(names)} && "
                         "[...pathfuse.state.results.values()].every(r => !r.stale)",
                         timeout=WAIT_MS)
    frames(pg)

    def box():
        return pg.evaluate("""(() => { const b = document.getElementById('results-box')
            .getBoundingClientRect(); const rows = [...document.querySelectorAll(
            '#results tbody tr')].map(r => r.getBoundingClientRect());
            return {h: b.height, top: b.top, bottom: b.bottom,
                    visible: rows.filter(r => r.bottom <= b.bottom + 0.5).length,
                    canvas: document.getElementById('canvas').getBoundingClientRect().height};
            })()""")

    b0 = box()
    assert b0["visible"] < len(names)  # at first it keeps the map big
    split = pg.locator("#split").bounding_box()
    x, y = split["x"] + split["width"] / 2, split["y"] + split["height"] / 2
    pg.mouse.move(x, y)
    pg.mouse.down()
    pg.mouse.move(x, y - 150, steps=5)
    pg.mouse.up()
    b1 = box()
    assert b1["h"] == pytest.approx(b0["h"] + 150, abs=2)
    assert b1["visible"] == len(names) and b1["canvas"] >= 200
    assert b1["canvas"] == pytest.approx(b0["canvas"] - 150, abs=2)  # the map gives way
    # the keyboard: down makes it smaller
    pg.focus("#split")
    pg.keyboard.press("ArrowDown")
    assert box()["h"] == pytest.approx(b1["h"] - 24, abs=2)


def settle(pg):
    """Wait until no plan is waiting or in flight and every answer is for the current scene."""
    pg.wait_for_function("pathfuse.idle()", timeout=WAIT_MS)
    frames(pg)


def occupied(pg):
    return pg.evaluate("pathfuse.state.map.occ.reduce((a, b) => a + b, 0)")


def test_undo_clear_random_maze_and_fit(page):
    pg = page
    walls = occupied(pg)
    start = pg.evaluate("pathfuse.state.start")
    # a painted stroke, undone and redone
    pg.check("input[name=tool][value=paint]")
    a = free_centre(pg, clear=0, far_from=start, min_dist=4, skip=0)
    pg.mouse.click(*screen(pg, *a))
    assert occupied(pg) == walls + 1
    pg.keyboard.press("Control+z")
    assert occupied(pg) == walls
    pg.keyboard.press("Control+Shift+z")
    assert occupied(pg) == walls + 1
    # clear: no wall; undo: all back
    pg.click("#clear-walls")
    assert occupied(pg) == 0
    settle(pg)
    assert results(pg)["astar"]["length"] == pytest.approx(10 * math.sqrt(2))
    pg.click("#undo")
    assert occupied(pg) == walls + 1
    # random walls of the density asked for, over the same size; start and goal connected
    goal = pg.evaluate("pathfuse.state.goal")
    pg.fill("#random-density", "0.3")
    pg.click("#random-map")
    pg.wait_for_function("pathfuse.state.map.name.startsWith('random')", timeout=WAIT_MS)
    settle(pg)
    assert occupied(pg) == round(0.3 * 225)
    assert pg.evaluate("[pathfuse.state.start, pathfuse.state.goal]") == [start, goal]
    assert results(pg)["astar"]["status"] == "SUCCESS"
    # a maze over a bigger map: corridors and walls, start and goal at its far corners
    pg.fill("#blank-w", "41")
    pg.fill("#blank-h", "31")
    pg.fill("#blank-res", "0.5")
    pg.click("#blank-make")
    pg.wait_for_function("pathfuse.state.map.width === 41")
    pg.click("#maze-map")
    pg.wait_for_function("pathfuse.state.map.name.startsWith('maze-')")
    settle(pg)
    got = results(pg)["astar"]
    s, g = pg.evaluate("[pathfuse.state.start, pathfuse.state.goal]")
    assert got["status"] == "SUCCESS" and got["length"] > 1.5 * math.dist(s, g)
    assert 0.3 < occupied(pg) / (41 * 31) < 0.75
    # fit: after zooming in, the whole map again
    fitted = pg.evaluate("pathfuse.view.scale")
    cx, cy = screen(pg, 5, 5)
    pg.mouse.move(cx, cy)
    pg.mouse.wheel(0, -600)
    frames(pg)
    assert pg.evaluate("pathfuse.view.scale") > 1.5 * fitted
    pg.click("#fit")
    assert pg.evaluate("pathfuse.view.scale") == pytest.approx(fitted)


def test_the_png_has_the_view_and_a_legend(page, tmp_path):
    from PIL import Image

    pg = page
    with pg.expect_download() as dl:
        pg.click("#png")
    assert dl.value.suggested_filename == "pathfuse-paper-5.png"
    path = tmp_path / "view.png"
    dl.value.save_as(path)
    w, h = pg.evaluate("[document.getElementById('canvas').width, "
                       "document.getElementById('canvas').height]")
    dpr = pg.evaluate("window.devicePixelRatio || 1")
    img = Image.open(path).convert("RGB")
    assert img.size[1] == h and w + 100 * dpr < img.size[0] < w + 300 * dpr
    px = img.load()
    view = img.crop((0, 0, w, h))
    # the view: both paths in their colours, the map's walls
    for rgb in ((0x00, 0x56, 0x8F), (0xDC, 0x18, 0x67), (38, 38, 44)):
        assert sum(1 for p in view.getdata() if p == rgb) > 100, rgb
    # the legend beside it, on white: a line of each planner's colour
    x = w + round(20 * dpr)
    assert px[x, round(58 * dpr)] == (0x00, 0x56, 0x8F)
    assert px[x, round(76 * dpr)] == (0xDC, 0x18, 0x67)
    assert px[img.size[0] - 2, h - 2] == (255, 255, 255)


@pytest.mark.parametrize("width, height", [(390, 844), (1400, 900)])
def test_the_layout_at_a_phone_and_a_desktop_width(browser, server, width, height, tmp_path):
    pg = browser.new_page(viewport={"width": width, "height": height})
    try:
        pg.goto(server)
        pg.wait_for_selector("body[data-planned]", timeout=WAIT_MS)
        frames(pg)
        out = Path(os.environ.get("PATHFUSE_SHOTS", tmp_path)) / f"page-{width}.png"
        pg.screenshot(path=str(out))
        lay = pg.evaluate("""(() => { const r = (id) => document.getElementById(id)
            .getBoundingClientRect();
            return {scroll: document.documentElement.scrollWidth, canvas: r('canvas'),
                    toolbar: [...document.querySelectorAll('#toolbar button, #toolbar label')]
                      .map(e => e.getBoundingClientRect().right),
                    table: r('results-box'), side: r('side')}; })()""")
        assert lay["scroll"] <= width  # nothing sticks out sideways
        assert max(lay["toolbar"]) <= width
        if width < 700:
            assert lay["canvas"]["width"] >= width - 2 and lay["canvas"]["height"] >= 350
            assert lay["table"]["top"] >= lay["canvas"]["bottom"]
            assert lay["side"]["top"] >= lay["table"]["bottom"]  # the controls below
            # the map fills the width
            wm = pg.evaluate("pathfuse.state.map.width * pathfuse.view.scale")
            assert wm >= 0.9 * width
        else:
            assert lay["canvas"]["width"] >= 900 and lay["canvas"]["height"] >= 600
            assert lay["side"]["right"] <= lay["canvas"]["left"]
        # the start can be dragged at this size
        goal = pg.evaluate("pathfuse.state.goal")
        target = free_centre(pg, clear=0, far_from=goal, min_dist=3, skip=40)
        before = planned(pg)
        pg.mouse.move(*screen(pg, *goal))
        pg.mouse.down()
        pg.mouse.move(*screen(pg, *target), steps=4)
        pg.mouse.up()
        replanned(pg, before)
        assert results(pg)["astar"]["goal"] == pytest.approx(target, abs=0.05)
    finally:
        pg.close()
