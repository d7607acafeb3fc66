"""Take the two screenshots of ``pathfuse serve`` in the docs (docs/serve.png and
docs/serve-episode.png) with Debian's chromium driven by Playwright, as
tests/test_web_browser.py drives it.

Usage: ``python benchmarks/screenshots.py docs/serve.png docs/serve-episode.png``

The first shows the paper's map (seed 0, as the page opens) with astar, fusion and ref7,
the potential field, the force arrows and the fusion's r1 circle at step 11; the second
the crossing scenario's episode with the fusion, paused at 55 % of its ticks.
"""

import socket
import subprocess
import sys
import time
import urllib.request

from playwright import sync_api

ARGS = ["--headless=new", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-dev-shm-usage"]
W = 600_000  # a cold numba cache compiles the planners on the first plans
with socket.socket() as s:
    s.bind(("127.0.0.1", 0)); port = s.getsockname()[1]
proc = subprocess.Popen([sys.executable, "-m", "pathfuse.cli", "serve", "--port", str(port)],
                        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
url = f"http://127.0.0.1:{port}/"
try:
    for _ in range(600):
        try:
            urllib.request.urlopen(url + "api/maps", timeout=2); break
        except OSError:
            time.sleep(0.2)
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path="/usr/bin/chromium", args=ARGS)
        pg = b.new_page(viewport={"width": 1400, "height": 860})
        pg.goto(url)
        pg.wait_for_selector("body[data-ready]", timeout=W)
        pg.wait_for_selector("body[data-planned]", timeout=W)
        def planned(): return int(pg.evaluate("document.body.dataset.planned"))
        for name in ("fusion", "ref7"):
            pg.check(f"input[data-planner={name}]")
        pg.wait_for_function("pathfuse.state.results.size === 3 && "
                             "[...pathfuse.state.results.values()].every(r => !r.stale)", timeout=W)
        for lay in ("#layer-heat", "#layer-arrows", "#layer-attract"):
            pg.check(lay)
        time.sleep(3)
        pg.locator("#attract-step").fill("11")
        time.sleep(2)
        print(pg.evaluate("Object.keys(Object.fromEntries(window.pathfuse.state.results))"))
        pg.screenshot(path=sys.argv[1])
        # an episode of the crossing scenario
        for lay in ("#layer-heat", "#layer-arrows", "#layer-attract"):
            pg.uncheck(lay)
        opts = pg.evaluate("[...document.querySelectorAll('#scenario-select option')].map(o => [o.value, o.textContent])")
        print(opts)
        val = next(v for v, t in opts if "crossing" in t)
        pg.select_option("#scenario-select", val)
        pg.click("#scenario-load")
        time.sleep(3)
        pg.select_option("#sim-planner", "fusion")
        pg.click("#sim-run")
        pg.wait_for_selector("body[data-episode]", timeout=W)
        pg.wait_for_selector("body[data-playback=ended]", timeout=W)
        n = int(pg.evaluate("pathfuse.player.ep.n_ticks"))
        pg.locator("#time").fill(str(int(n * 0.55)))
        time.sleep(1)
        print(pg.inner_text("#outcome"))
        pg.screenshot(path=sys.argv[2])
        b.close()
finally:
    proc.terminate(); proc.wait(timeout=10)
