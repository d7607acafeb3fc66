"""Take the two screenshots of ``pathfuse serve`` in the docs (docs/serve.png and
docs/serve-episode.png) with Debian's chromium driven by Playwright, as
tests/test_web_browser.py drives it.

Usage: ``python benchmarks/screenshots.py docs/serve.png docs/serve-episode.png``

The first shows the paper's map as the page opens it, with astar, fusion and ref7, the
potential field, the force arrows and the fusion's r1 circle at step 11; the second the
crossing scenario's episode with the fusion, paused at 55 % of its ticks.
"""

from __future__ import annotations

import socket
import subprocess
import sys
import time
import urllib.request

from playwright import sync_api

ARGS = ["--headless=new", "--no-sandbox", "--disable-gpu", "--no-first-run",
        "--disable-dev-shm-usage"]
WAIT_MS = 600_000  # a cold numba cache compiles the planners on the first plans
LAYERS = ("#layer-heat", "#layer-arrows", "#layer-attract")


def _serve() -> tuple[subprocess.Popen[str], str]:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proc = subprocess.Popen([sys.executable, "-m", "pathfuse.cli", "serve", "--port", str(port)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    url = f"http://127.0.0.1:{port}/"
    for _ in range(600):
        try:
            with urllib.request.urlopen(url + "api/maps", timeout=2):
                break
        except OSError:
            time.sleep(0.2)
    return proc, url


def main(plan_png: str, episode_png: str) -> None:
    proc, url = _serve()
    try:
        with sync_api.sync_playwright() as p:
            browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=ARGS)
            pg = browser.new_page(viewport={"width": 1400, "height": 860})
            pg.goto(url)
            pg.wait_for_selector("body[data-ready]", timeout=WAIT_MS)
            pg.wait_for_selector("body[data-planned]", timeout=WAIT_MS)
            for name in ("fusion", "ref7"):
                pg.check(f"input[data-planner={name}]")
            pg.wait_for_function("pathfuse.state.results.size === 3 && [...pathfuse.state"
                                 ".results.values()].every(r => !r.stale)", timeout=WAIT_MS)
            for layer in LAYERS:
                pg.check(layer)
            time.sleep(3)
            pg.locator("#attract-step").fill("11")
            time.sleep(2)
            pg.screenshot(path=plan_png)
            for layer in LAYERS:
                pg.uncheck(layer)
            options = pg.evaluate("[...document.querySelectorAll('#scenario-select option')]"
                                  ".map(o => [o.value, o.textContent])")
            pg.select_option("#scenario-select", next(v for v, t in options if "crossing" in t))
            pg.click("#scenario-load")
            time.sleep(3)
            pg.select_option("#sim-planner", "fusion")
            pg.click("#sim-run")
            pg.wait_for_selector("body[data-episode]", timeout=WAIT_MS)
            pg.wait_for_selector("body[data-playback=ended]", timeout=WAIT_MS)
            n = int(pg.evaluate("pathfuse.player.ep.n_ticks"))
            pg.locator("#time").fill(str(int(n * 0.55)))
            time.sleep(1)
            print(pg.inner_text("#outcome"))
            pg.screenshot(path=episode_png)
            browser.close()
    finally:
        proc.terminate()
        proc.wait(timeout=10)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
