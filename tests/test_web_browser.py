"""The page of ``pathfuse serve`` in a real browser: Debian's chromium driven by Playwright.

CI (``.ci/run``) installs chromium with apt-get, so these tests run there; they are
skipped, saying why, only on a machine with no chromium.  The server is the real
command (``python -m pathfuse.cli serve``) on a free loopback port.

What a user does: load the page, paint an obstacle, drag the goal, run fusion and A*
(both paths drawn, their lengths in the table), toggle the potential layer, place ten
moving discs and play an episode to its end (the frame rate is measured and printed),
upload a malformed map and read the error, and zoom and pan a 1024 x 1024 map.
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


@pytest.fixture(scope="module")
def server():
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
