"""What ``pathfuse serve`` costs: server time of /api/plan and /api/field, and the page's
frame rate while it plays an episode with 10 moving discs.

The server is the real command (``python -m pathfuse.cli serve``) on a loopback port;
requests go over HTTP as the page sends them.  For each request the script prints the
median round trip (wall, over ``--repeat`` requests), the server process's CPU time per
request (from /proc), and the same work done the ways a user would otherwise do it, in
the same run:

* ``plan()``: :func:`pathfuse.plan` in this process (no HTTP, no JSON): the floor;
* ``pathfuse plan --json``: the command line, one process per query (what a script
  without the server does);
* for the field, :func:`pathfuse.web.layers.potential_field` in this process.

Maps: the paper's map (seed 5, start (1, 1), goal (11, 11)) and a 1024 x 1024 map:
Boston_0_1024 from ``--data`` (MovingAI, uploaded once through /api/maps; the query is
the scenario file's last line) or, without the data, a seeded random 1024 x 1024 map.
numba compilation is done by a warm-up request before any timing.  The playback is
measured in Debian's chromium (Playwright) with ``requestAnimationFrame`` timestamps at
1x speed; it needs /usr/bin/chromium.

Usage::

    python benchmarks/bench_web.py [--data DIR] [--repeat 200] [--repeat-big 10] [--cli 5]
        [--no-browser]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import socket
import statistics
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = ROOT.parent / "shared" / "data" / "movingai"
TICK = os.sysconf("SC_CLK_TCK")


def cpu_s(pid: int) -> float:
    """User + system CPU seconds so far of a process and its worker processes (the live ones,
    and those it has reaped)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    total = sum(int(f) for f in fields[11:15])  # utime, stime, cutime, cstime
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            children = (task / "children").read_text().split()
        except OSError:
            continue
        for child in children:
            try:
                f = Path(f"/proc/{child}/stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            total += int(f[11]) + int(f[12])
    return total / TICK


def post(url: str, body: dict) -> dict:
    req = urllib.request.Request(url, data=json.dumps(body).encode(),
                                 headers={"Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=120) as r:
            return json.loads(r.read())
    except urllib.error.HTTPError as exc:
        raise SystemExit(f"{url}: HTTP {exc.code}: {exc.read().decode()}") from None


def upload(url: str, path: Path) -> dict:
    boundary = "pathfuse-bench-boundary"
    body = (f"--{boundary}\r\nContent-Disposition: form-data; name=\"file\"; "
            f"filename=\"{path.name}\"\r\nContent-Type: application/octet-stream\r\n\r\n"
            ).encode() + path.read_bytes() + f"\r\n--{boundary}--\r\n".encode()
    req = urllib.request.Request(url, data=body, headers={
        "Content-Type": f"multipart/form-data; boundary={boundary}"})
    with urllib.request.urlopen(req, timeout=120) as r:
        return json.loads(r.read())


def timed_requests(pid: int, fn, repeat: int) -> tuple[float, float, dict]:
    fn()  # warm-up: numba compilation, per-map buffers
    walls = []
    c0 = cpu_s(pid)
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        walls.append(time.perf_counter() - t0)
    return statistics.median(walls), (cpu_s(pid) - c0) / repeat, out


def median_time(fn, repeat: int) -> tuple[float, float]:
    """Median wall time and mean CPU time (this process) of ``fn()``, after one warm-up."""
    fn()
    out = []
    c0 = time.process_time()
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return statistics.median(out), (time.process_time() - c0) / repeat


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA)
    ap.add_argument("--repeat", type=int, default=200, help="requests per paper-map case")
    ap.add_argument("--repeat-big", type=int, default=10, help="requests per 1024-map case")
    ap.add_argument("--cli", type=int, default=5, help="command-line runs per query")
    ap.add_argument("--no-browser", action="store_true")
    args = ap.parse_args()

    import pathfuse
    from pathfuse.web.layers import potential_field

    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} at start")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    base = f"http://127.0.0.1:{port}"
    proc = subprocess.Popen([sys.executable, "-m", "pathfuse.cli", "serve", "--port",
                             str(port), "--no-warm", "--budget", "120"],
                            stderr=subprocess.DEVNULL)
    try:
        for _ in range(300):
            try:
                urllib.request.urlopen(base + "/api/maps", timeout=2).close()
                break
            except OSError:
                time.sleep(0.1)
        big = args.data / "Boston_0_1024.map"
        if big.exists():
            bid = upload(base + "/api/maps", big)["id"]
            from pathfuse.io.scenario import read_scen

            grid = pathfuse.load_map(big)
            q = read_scen(args.data / "Boston_0_1024.map.scen", grid)[-1]
            big_map, big_name = {"id": bid}, f"Boston_0_1024 ({q.optimal_length:.0f} m query)"
            start, goal = list(q.start), list(q.goal)
            big_cli = ["--map", str(big)]
        else:
            ends = [[0.5, 0.5], [1023.5, 1023.5]]
            spec = {"random": {"size": [1024, 1024], "density": 0.2, "seed": 1,
                               "keep_free": ends, "connect": [ends]}}
            bid = post(base + "/api/map", {"map": spec})["id"]
            grid = pathfuse.map_from_spec(spec)
            big_map, big_name, (start, goal) = {"id": bid}, "random 1024 x 1024", ends
            big_cli = None
        rows = []
        cases = [("paper seed 5", "astar", {"map": "paper", "seed": 5},
                  pathfuse.load_map("paper", seed=5), [1.0, 1.0], [11.0, 11.0],
                  ["--map", "paper", "--seed", "5"]),
                 ("paper seed 5", "fusion", {"map": "paper", "seed": 5},
                  pathfuse.load_map("paper", seed=5), [1.0, 1.0], [11.0, 11.0],
                  ["--map", "paper", "--seed", "5"]),
                 (big_name, "astar", {"map": big_map}, grid, start, goal, big_cli),
                 (big_name, "fusion", {"map": big_map}, grid, start, goal, big_cli)]
        for name, planner, mref, g, s0, g0, cli in cases:
            body = {**mref, "start": s0, "goal": g0, "planner": planner}
            n = args.repeat if g.occupied.size < 100_000 else args.repeat_big
            wall, cpu, out = timed_requests(proc.pid, lambda b=body: post(base + "/api/plan", b),
                                            n)
            lib = median_time(lambda g=g, s0=s0, g0=g0, p=planner:
                              pathfuse.plan(g, s0, g0, planner=p), n)
            cli_s = None
            if cli is not None and args.cli:
                argv = [sys.executable, "-m", "pathfuse.cli", "plan", *cli, "--start",
                        f"{s0[0]},{s0[1]}", "--goal", f"{g0[0]},{g0[1]}", "--planner",
                        planner, "--json"]
                cli_s = median_time(lambda a=argv: subprocess.run(a, capture_output=True,
                                                                  check=True), args.cli)[0]
            rows.append(("/api/plan", name, planner, out["status"], n, wall, cpu, lib, cli_s))
        fbody = {"map": big_map, "goal": goal, "planner": "fusion"}
        wall, cpu, out = timed_requests(proc.pid, lambda: post(base + "/api/field", fbody),
                                        args.repeat_big * 3)
        lib = median_time(lambda: potential_field(grid, tuple(goal), 40.0, 5.0, 2.0),
                          args.repeat_big * 3)
        rows.append(("/api/field", big_name, "fusion gains", f"{out['heat']['shape']}",
                     args.repeat_big * 3, wall, cpu, lib, None))
    finally:
        proc.terminate()
        proc.wait(timeout=10)

    print("\nwall: median round trip on loopback (new connection per request, as urllib does);"
          " server CPU: mean per request, from /proc (10 ms ticks, so a mean over n);\n"
          "in-process: pathfuse.plan() / potential_field() in this process, median wall and "
          "mean CPU; CLI: one `pathfuse plan --json` process per query, median wall\n")
    print("| endpoint | map | planner | answer | n | round trip ms | server CPU ms | "
          "in-process ms (CPU) | round trip / in-process | CLI process ms | CLI / round trip |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for ep, name, planner, status, n, wall, cpu, lib, cli_s in rows:
        cli_txt = "–" if cli_s is None else f"{1e3 * cli_s:.0f}"
        ratio = "–" if cli_s is None else f"{cli_s / wall:.0f}x"
        print(f"| {ep} | {name} | {planner} | {status} | {n} | {1e3 * wall:.2f} | "
              f"{1e3 * cpu:.2f} | {1e3 * lib[0]:.3f} ({1e3 * lib[1]:.3f}) | {wall / lib[0]:.1f}x "
              f"| {cli_txt} | {ratio} |")
    print(f"\nload average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} at the end")
    if not args.no_browser:
        playback()


def playback() -> None:
    """The page's frame rate while it plays an episode with 10 discs (1x speed)."""
    chromium = "/usr/bin/chromium"
    if not os.path.exists(chromium):
        print("\nplayback: no /usr/bin/chromium, skipped")
        return
    from playwright.sync_api import sync_playwright

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proc = subprocess.Popen([sys.executable, "-m", "pathfuse.cli", "serve", "--port",
                             str(port)], stderr=subprocess.DEVNULL)
    args = ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic",
            "--no-first-run", "--disable-background-networking", "--disable-component-update",
            "--disable-sync", "--disable-dev-shm-usage"]
    try:
        for _ in range(300):
            try:
                urllib.request.urlopen(f"http://127.0.0.1:{port}/api/maps", timeout=2).close()
                break
            except OSError:
                time.sleep(0.1)
        with sync_playwright() as p:
            b = p.chromium.launch(executable_path=chromium, args=args)
            pg = b.new_page(viewport={"width": 1400, "height": 900})
            pg.goto(f"http://127.0.0.1:{port}/")
            pg.wait_for_selector("body[data-planned]", timeout=180_000)
            # an open 20 m x 15 m hall (40 x 30 cells of 0.5 m), ten discs across the route
            pg.fill("#blank-w", "40")
            pg.fill("#blank-h", "30")
            pg.fill("#blank-res", "0.5")
            pg.click("#blank-make")
            pg.wait_for_function("window.pathfuse.state.map.width === 40")
            pg.evaluate("""() => { const s = window.pathfuse.scene;
                for (let k = 0; k < 10; k++) s.add({position: [3 + (k % 5) * 3.5,
                    4 + Math.floor(k / 5) * 6], velocity: [0.4 * Math.cos(k), 0.4 * Math.sin(k)],
                    radius: 0.3}); }""")
            pg.click("#sim-run")
            pg.wait_for_function("document.body.dataset.playback === 'ended' || "
                                 "document.getElementById('sim-error').textContent !== ''",
                                 timeout=300_000)
            err = pg.inner_text("#sim-error")
            if err:
                raise SystemExit(f"playback: the episode did not run: {err}")
            st = pg.evaluate("window.pathfuse.player.stats")
            n = pg.evaluate("window.pathfuse.player.ep.n_ticks")
            status = pg.evaluate("window.pathfuse.player.ep.status")
            b.close()
    finally:
        proc.terminate()
        proc.wait(timeout=10)
    print(f"\nplayback in chromium (headless, {chromium}): 20 m x 15 m hall, {st['discs']} discs, "
          f"{n} ticks ({status}), 1x speed: {st['fps']:.1f} frames/s over {st['seconds']:.1f} s; "
          f"frame interval median {st['median_frame_ms']:.1f} ms, 95th percentile "
          f"{st['p95_frame_ms']:.1f} ms, longest {st['max_frame_ms']:.1f} ms")
    print(f"load average {os.getloadavg()[0]:.2f} at the end")


if __name__ == "__main__":
    main()
