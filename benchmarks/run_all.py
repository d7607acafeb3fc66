"""Re-measure the speed figures the documentation quotes and write them into it.

Each figure of the generated speed blocks of ``docs/speed.md`` comes from one benchmark's
JSON output in ``benchmarks/results/``; this script runs the benchmarks, keeps
their JSON there, and rewrites each block between its markers::

    <!-- speed:NAME begin: written by benchmarks/run_all.py from benchmarks/results/NAME.json -->
    ...
    <!-- speed:NAME end -->

so that no figure in those blocks is typed by hand.  ``tests/test_speed_docs.py``
checks that every block equals what :func:`render` makes of its JSON.

Blocks and their benchmarks:

* ``peers``: ``bench_astar.py`` (A* against scipy, tcod and networkx under both corner
  rules, wall time);
* ``search``: ``bench_search.py`` (A*, jump point search, scipy, pyastar2d on the
  hardest and on mixed MovingAI queries; expansions per second at 4096 x 4096);
* ``plan``: ``bench_plan.py`` (the glue around the search, per map, and a tiny query);
* ``startup``: ``bench_startup.py`` (import, ``--help``, a first plan on a cold and a
  warm numba cache);
* ``stepping``: ``bench_stepping.py`` (APF and fusion steps per second, fusion over A*);
* ``controllers``: ``bench_controllers.py`` (every online controller, both robot models);
* ``shield``: ``bench_shield.py`` (the safety shield per command);
* ``mppi``: ``bench_mppi.py`` (mppi against dwa per tick);
* ``metrics``: ``bench_metrics.py`` (``evaluate()`` against its predecessor and shapely);
* ``anyangle``: ``bench_anyangle.py`` (Theta*, Lazy Theta*, smoothed A*, ``shortest``).

Each JSON records the commit of ``src/`` it measured (``-dirty`` for uncommitted changes).

Usage::

    python benchmarks/run_all.py [--only NAME ...] [--no-run] [--check]

``--no-run`` only rewrites the speed page from the JSON already there; ``--check``
rewrites nothing and exits 1 when a block differs from its JSON.  The whole run takes
about half an hour on 2 cores (``--only`` to run fewer); the machine's load is
part of every block, as the machines are shared.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RESULTS = HERE / "results"
SPEED_PAGE = ROOT / "docs" / "speed.md"  # the speed page (the README links to it)
BLOCKS = ("search", "peers", "plan", "startup", "stepping", "controllers", "shield", "mppi",
          "metrics", "anyangle")


# ----------------------------------------------------------------------------- formatting
def ms(x: float) -> str:
    """Milliseconds, three significant digits (at least one decimal below 10)."""
    if x >= 100:
        return f"{x:.0f} ms"
    if x >= 10:
        return f"{x:.1f} ms"
    if x >= 1:
        return f"{x:.2f} ms"
    return f"{x * 1000:.0f} µs" if x < 0.1 else f"{x:.3f} ms"


def ratio(x: float) -> str:
    return f"{x:.2f}" if x < 10 else f"{x:.1f}"


def machine_line(m: dict[str, Any], load_end: float | None, command: str) -> str:
    end = f" and {load_end} at the end" if load_end is not None else ""
    on = f" on commit {m['commit']}" if m.get("commit") else ""
    return (f"Measured with `{command}`{on} on {m['machine']}, {m['cores']} cores, load average "
            f"{m['load']} at the start{end} (the machine is shared), Python {m['python']}"
            + (f", numba {m['numba']}" if "numba" in m else "") + ".")


# ----------------------------------------------------------------------------- blocks
def render_search(r: dict[str, Any]) -> str:
    out = [machine_line(r["machine"], r["load_end"], "python benchmarks/bench_search.py"),
           "CPU time per query, median; in brackets the tool's time over `plan()`'s (planner "
           "`astar` with its defaults), the median of the per-query ratios: above 1 the tool "
           "is slower. numba compilation, the per-map buffers and the component labels are "
           "made before any clock starts; scipy's graph is built beforehand."]
    for part, title in (("hard", "Hardest queries: the {n} longest scenario lines of each map"),
                        ("mixed", "Mixed queries: {n} scenario lines of each map drawn at "
                                  "random (seed 0)")):
        n = next(iter(r["maps"].values()))[part]["queries"]
        out += ["", f"{title.format(n=n)}:", "",
                "| map | `plan()` | `plan()`, octile | JPS searcher | scipy `dijkstra` "
                "| pyastar2d, C++ entry | pyastar2d `astar_path` |",
                "|---|---|---|---|---|---|---|"]
        for name, v in r["maps"].items():
            t = v[part]["tools"]
            cells = [ms(t["astar"]["cpu_ms"])]
            for tool in ("astar-octile", "jps", "scipy", "pyastar2d", "pyastar2d-public"):
                cells.append(f"{ms(t[tool]['cpu_ms'])} ({ratio(t[tool]['cpu_ratio'])})"
                             if tool in t else "n/a")
            out.append(f"| {name} | " + " | ".join(cells) + " |")
    spans = [v[p]["tools"]["pyastar2d"]["len_over_opt"] for v in r["maps"].values()
             for p in ("hard", "mixed") if "pyastar2d" in v[p]["tools"]]
    jh = [v["hard"]["jps_vs_search_octile"] for v in r["maps"].values()]
    jm = [v["mixed"]["jps_vs_search_octile"] for v in r["maps"].values()]
    out += ["", ""]
    if spans:  # pyastar2d is optional (not in the bench extra)
        out[-1] = (f"pyastar2d's paths, measured under the MovingAI rules, are "
                   f"{min(s[0] for s in spans):.2f}–{max(s[1] for s in spans):.2f} times the "
                   f"optimum. Its C++ entry point (`pyastar2d.astar.astar`) is timed on "
                   f"weights flattened once, the stricter comparison, by which the targets "
                   f"are judged; `astar_path`, the function its users call, also checks "
                   f"the weights' minimum and flattens the grid on every call. ")
    out[-1] += (f"Against the octile A* searcher (the same level: no `plan()` around either), "
                f"JPS is {min(jh):.1f}–{max(jh):.1f}× faster on the hardest queries and "
                f"{min(jm):.1f}–{max(jm):.1f}× on the mixed ones.")
    if "big" in r:
        b = r["big"]
        e, o, j = b["astar-euclidean"], b["astar-octile"], b["jps"]
        out += ["", f"{b['side']} × {b['side']} cells (Boston_0_1024 scaled up, each cell a "
                f"block), its {b['queries']} longest scenario lines scaled: A* "
                f"{e['mexp_per_cpu_s']:.1f} M expansions per CPU second with the Euclidean "
                f"heuristic ({ms(e['cpu_ms'])}, {e['expansions']:,} expansions per query) and "
                f"{o['mexp_per_cpu_s']:.1f} M with the octile one ({ms(o['cpu_ms'])}); JPS "
                f"{ms(j['cpu_ms'])}. A new map of that size costs once: the A* buffers "
                f"{b['astar_buffers_cpu_s']:.2f} s of CPU, the component labels "
                f"{b['labels_cpu_s']:.2f} s (made only when a search first finds no path)."]
    return "\n".join(out)


def render_peers(r: dict[str, Any]) -> str:
    rows = r["rows"]
    maps = list(dict.fromkeys(x["map"] for x in rows))

    def row(m: str, rule: str, tool: str) -> dict[str, Any] | None:
        return next((x for x in rows if x["map"] == m and x["rule"] == rule
                     and x["tool"] == tool), None)

    def cell(x: dict[str, Any] | None, with_ratio: bool = True) -> str:
        if x is None:
            return "n/a"
        if not with_ratio:
            return ms(x["median_ms"])
        return f"{ms(x['median_ms'])} ({ratio(x['ratio_vs_pathfuse_euclidean'])})"

    out = [machine_line(r["machine"], r["load_end"], "python benchmarks/bench_astar.py"),
           f"{r['queries']} scenario lines per map drawn at random (seed {r['seed']}), one "
           "query at a time, interleaved; wall time per query, median; in brackets the "
           "tool's time over pathfuse's with the Euclidean heuristic under the same corner "
           "rule (above 1: pathfuse is faster). Graph builds, per-map buffers and numba "
           "compilation are excluded for every tool.", "",
           "| map, no corner cutting | pathfuse, Euclidean | pathfuse, octile | scipy "
           "`dijkstra` | tcod `CustomGraph` | networkx `astar_path` |",
           "|---|---|---|---|---|---|"]
    for m in maps:
        rule = "no corner cutting"
        tc = [x for x in (row(m, rule, "tcod CustomGraph, new Pathfinder"),
                          row(m, rule, "tcod CustomGraph, reused Pathfinder")) if x]
        best = min(tc, key=lambda x: x["median_ms"]) if tc else None
        out.append(f"| {m} | {cell(row(m, rule, 'pathfuse euclidean'), False)} | "
                   f"{cell(row(m, rule, 'pathfuse octile'))} | "
                   f"{cell(row(m, rule, 'scipy dijkstra'))} | {cell(best)} | "
                   f"{cell(row(m, rule, 'networkx astar_path'))} |")
    out += ["", "| map, corner cutting | pathfuse, Euclidean | pathfuse, octile | scipy "
            "`dijkstra` | tcod `path2d` | tcod `AStar` (float) |", "|---|---|---|---|---|---|"]
    for m in maps:
        rule = "corner cutting"
        out.append(f"| {m} | {cell(row(m, rule, 'pathfuse euclidean'), False)} | "
                   f"{cell(row(m, rule, 'pathfuse octile'))} | "
                   f"{cell(row(m, rule, 'scipy dijkstra'))} | "
                   f"{cell(row(m, rule, 'tcod path2d'))} | "
                   f"{cell(row(m, rule, 'tcod old AStar (float)'))} |")
    dev = max((x["max_rel_length_dev"] for x in rows if x["tool"] == "tcod old AStar (float)"),
              default=0.0)
    out += ["", f"tcod's `CustomGraph` gets the rule without corner cutting from a per-edge "
            f"`condition` array and integer costs (√2 approximated; the faster of a new and a "
            f"reused `Pathfinder` is shown); scipy has no A* and no early exit, so it "
            f"searches the whole map; tcod's old `AStar` stops when the goal is first reached, "
            f"not expanded, with float32 costs, so its paths need not be optimal (here at most "
            f"{100 * dev:.2f} % over pathfuse's)."]
    return "\n".join(out)


def render_plan(r: dict[str, Any]) -> str:
    out = [machine_line(r["machine"], r["load_end"], "python benchmarks/bench_plan.py"),
           "Wall time per query, median of the seeded sample; `plan()` is the public call, "
           "the kernel the searcher alone, scipy its `dijkstra` with the walk back along the "
           "predecessors.", "",
           "| map | `plan()` µs | kernel µs | plan / kernel | scipy µs | scipy / plan |",
           "|---|---|---|---|---|---|"]
    for name, v in r["maps"].items():
        out.append(f"| {name} | {v['plan_us']:.1f} | {v['kernel_us']:.1f} | "
                   f"{v['plan_us'] / v['kernel_us']:.2f} | {v['scipy_us']:.1f} | "
                   f"{v['scipy_us'] / v['plan_us']:.1f}× |")
    t = r["tiny"]
    out += ["", f"A tiny query (two neighbouring cells of Boston_0_1024, {t['expansions']} "
            f"expansions) costs {t['plan_us']:.1f} µs in `plan()` and {t['kernel_us']:.1f} µs "
            f"in the searcher (CPU {t['plan_cpu_us']:.1f} and {t['kernel_cpu_us']:.1f} µs): "
            f"the fixed cost of a call is {t['plan_us'] - t['kernel_us']:.1f} µs."]
    return "\n".join(out)


STARTUP_TARGETS_S = {"astar": 2.0, "fusion": 5.0}  # issue 21: CPU of a cold first plan


def render_startup(r: dict[str, Any]) -> str:
    out = [machine_line(r["machine"], r["load_end"], "python benchmarks/bench_startup.py"),
           "Whole processes, CPU time (user + system) and wall time, medians; a cold run has "
           "`NUMBA_CACHE_DIR` pointed at a new empty folder.", "",
           "| command | CPU | wall |", "|---|---|---|",
           f"| `python -c \"import pathfuse\"` | {r['import']['cpu_s']:.2f} s | "
           f"{r['import']['wall_s']:.2f} s |",
           f"| `pathfuse --help` | {r['help']['cpu_s']:.2f} s | {r['help']['wall_s']:.2f} s |"]
    kinds = {"cold": "cold cache (kernels interpreted)",
             "compile": "cold cache, `PATHFUSE_KERNELS=compiled` (kernels compiled)",
             "warm": "warm cache (kernels loaded)"}
    for key in r:
        if key.startswith("plan-"):
            for kind, said in kinds.items():
                if kind not in r[key]:
                    continue
                s = r[key][kind]
                span = (f" ({s['cpu_min_s']:.1f}–{s['cpu_max_s']:.1f})"
                        if kind != "warm" and s["runs"] > 1 else "")
                out.append(f"| `pathfuse plan --map paper --planner {key[5:]}`, {said} "
                           f"| {s['cpu_s']:.2f} s{span} | {s['wall_s']:.2f} s |")
    if "numba" in r:
        n = r["numba"]
        out.append(f"| `import numba` and one first compilation (of `lambda a: a + 1`) "
                   f"| {n['cpu_s']:.2f} s | {n['wall_s']:.2f} s |")
    targets = [(p, t) for p, t in STARTUP_TARGETS_S.items() if f"plan-{p}" in r]
    if targets:
        said = "; ".join(
            f"{p} ≤ {t:g} s: {'met' if r[f'plan-{p}']['cold']['cpu_s'] <= t else 'not met'} "
            f"({r[f'plan-{p}']['cold']['cpu_s']:.2f} s)" for p, t in targets)
        out += ["", f"Cold-start targets of issue 21 (CPU, median): {said}."]
        comp = [(p, r[f"plan-{p}"]["compile"]["cpu_s"]) for p, _ in targets
                if "compile" in r[f"plan-{p}"]]
        if comp:
            from pathfuse.tier import MAX_CELLS

            side = math.isqrt(MAX_CELLS)
            out[-1] += (" The cold runs meet them by running the kernels interpreted, which "
                        f"the default rule does on a map of at most {side} × {side} cells; a first "
                        "plan that compiles (a larger map, or `PATHFUSE_KERNELS=compiled`) "
                        "still takes " + ", ".join(f"{c:.2f} s ({p})" for p, c in comp) + ".")
    return "\n".join(out)


def render_stepping(r: dict[str, Any]) -> str:
    m = r["machine"]
    side = r["big_map"]["side"]
    return "\n".join([
        machine_line(m, r["load_end"], "python benchmarks/bench_stepping.py"),
        "",
        f"* The stepping loops run at {r['apf_steps_per_s_paper'] / 1e6:.1f} million APF "
        f"steps/s and {r['fusion_steps_per_s_paper'] / 1e6:.1f} million fusion steps/s on the "
        f"{r['paper_seeds']} paper maps, and at {r['apf_big_over_paper']:.2f} and "
        f"{r['fusion_big_over_paper']:.2f} times those rates on a {side} × {side} map: the "
        f"repulsion reads a local window, so a step costs the same on a map of any size.",
        f"* Fusion planning at its default step costs {r['fusion_over_astar_median']:.2f}× the "
        f"A* planning on the same paper maps (median {r['fusion_time_median_s'] * 1e6:.1f} µs "
        f"against {r['astar_time_median_s'] * 1e6:.1f} µs; the paper reports 1.56× in "
        f"MATLAB); as whole `plan()` calls, {r['fusion_over_astar_wall_median']:.2f}×. The "
        f"fusion's time is mostly its stepping, so a faster A* raises this ratio.",
    ])


def _us(x: float) -> str:
    """A time given in microseconds, three significant digits, in ms from 1 ms up."""
    if x >= 1000:
        return ms(x / 1000)
    return f"{x:.0f} µs" if x >= 100 else f"{x:.1f} µs" if x >= 10 else f"{x:.2f} µs"


def _met(ok: bool) -> str:
    return "met" if ok else "**not met**"


DWA_TICKS_TARGET = 1500.0  # issue 21: simulated ticks per second, both robot models
SHIELD_TARGET_US = 200.0  # issue 17: the shield per command
MPPI_TARGET_MS = 20.0  # issue 17: mppi per tick on one core


def render_controllers(r: dict[str, Any]) -> str:
    sc = r["scenarios"]
    rows = r["rows"]
    names = list(dict.fromkeys(x["planner"] for x in rows))
    get = {(x["planner"], x["robot"]): x for x in rows}
    out = [machine_line(r["machine"], r["load_end"], "python benchmarks/bench_controllers.py"),
           f"Every online planner drives `pathfuse.simulate` on the {sc['shipped']} shipped "
           f"scenarios and {sc['generated']} generated ones ({sc['moving']} moving discs) with "
           "each robot model; numba compilation is kept out by a warm-up episode per planner "
           "and model. *Decision*: the median wall time of one control decision (the "
           "controller through the safety shield, and on a diff-drive robot the conversion to "
           "(v, ω)); *× real time*: decisions per second times the scenarios' `dt`; *ticks/s*: "
           "whole simulations (world stepping and bookkeeping included) per second of wall "
           "time and per second of the process's CPU time.", "",
           "| controller | holonomic: decision | × real time | ticks/s wall / CPU | diff-drive: "
           "decision | × real time | ticks/s wall / CPU |", "|---|---|---|---|---|---|---|"]
    for n in names:
        cells = []
        for model in ("holonomic", "diff-drive"):
            x = get.get((n, model))
            if x is None:
                cells += ["n/a"] * 3
                continue
            cells += [_us(x["decision_us"]), f"{x['x_real_time']:,.0f}",
                      f"{x['ticks_per_wall_s']:,.0f} / {x['ticks_per_cpu_s']:,.0f}"]
        out.append(f"| {n} | " + " | ".join(cells) + " |")
    dwa = [get[("dwa", m)] for m in ("holonomic", "diff-drive") if ("dwa", m) in get]
    if len(dwa) == 2:
        h, d = dwa
        ok = min(h["ticks_per_cpu_s"], d["ticks_per_cpu_s"]) >= DWA_TICKS_TARGET
        out += ["", f"Issue 21 asks dwa for at least {DWA_TICKS_TARGET:,.0f} ticks/s on both "
                f"robot models: {h['ticks_per_cpu_s']:,.0f} (holonomic) and "
                f"{d['ticks_per_cpu_s']:,.0f} (diff-drive) per CPU second, "
                f"{h['ticks_per_wall_s']:,.0f} and {d['ticks_per_wall_s']:,.0f} per wall second "
                f"at this load: {_met(ok)}."]
    return "\n".join(out)


def render_shield(r: dict[str, Any]) -> str:
    rows = r["rows"]
    out = [machine_line(r["machine"], r["load_end"], "python benchmarks/bench_shield.py"),
           f"The {r['states']} states of four BARN episodes (`tests/data/barn`, dwa driving the "
           "diff-drive Jackal-sized disc of 0.333 m at 2 m/s on 0.05 m cells); each call timed "
           f"{r['repeat']} times, the least kept; wall time. *Asked*: the shield on the command "
           "the robot applied, as `Controller.command` calls it; *adversarial*: on full speed "
           "at a random yaw rate, so the window search runs when that command has no safe "
           "stop; the straight-stop check is the test the shield replaced; a dwa decision for "
           "scale.", "", "| call | median | p95 | max |", "|---|---|---|---|"]
    for name, x in rows.items():
        out.append(f"| {name} | {_us(x['median_us'])} | {_us(x['p95_us'])} | "
                   f"{_us(x['max_us'])} |")
    worst = max(rows["shield (asked)"]["p95_us"], rows["shield (adversarial)"]["p95_us"])
    codes = ", ".join(f"{n} {c}" for n, c in r["adversarial_codes"].items() if c)
    out += ["", f"Outcomes of the adversarial commands: {codes}. Issue 17 asks at most "
            f"{_us(SHIELD_TARGET_US)} per command: the 95th percentile is {_us(worst)} at most "
            f"({_met(worst <= SHIELD_TARGET_US)})."]
    return "\n".join(out)


def render_mppi(r: dict[str, Any]) -> str:
    out = [machine_line(r["machine"], r["load_end"], "python benchmarks/bench_mppi.py"),
           f"mppi and dwa drive the same {r['episodes_per_controller']} episodes each: the four "
           "BARN worlds of `tests/data/barn` with the diff-drive Jackal-sized disc at 1 and "
           "2 m/s, and the example scenarios with a diff-drive and a holonomic robot; a "
           "decision's wall time (through the shield) and the process's CPU time per simulated "
           "tick; numba compilation kept out by a warm-up episode.", "",
           "| controller | episodes | ticks | decision median | p90 | CPU per tick | outcomes |",
           "|---|---|---|---|---|---|---|"]
    for x in r["rows"]:
        oc = ", ".join(f"{k} {v}" for k, v in x["outcomes"].items())
        out.append(f"| {x['controller']} | {x['episodes']} | {x['ticks']} | "
                   f"{x['median_ms']:.2f} ms | {x['p90_ms']:.2f} ms | "
                   f"{x['cpu_ms_per_tick']:.2f} ms | {oc} |")
    a = r["all"]
    worst = max(x["cpu_ms_per_tick"] for x in r["rows"] if x["controller"] == "mppi")
    out += ["", f"Over all episodes a decision takes {a['mppi']:.2f} ms for mppi and "
            f"{a['dwa']:.2f} ms for dwa ({a['mppi'] / a['dwa']:.1f}×). Issue 17 asks mppi for at "
            f"most {MPPI_TARGET_MS:.0f} ms per tick on one core at its defaults: at most "
            f"{worst:.2f} ms of CPU per simulated tick over the groups above "
            f"({_met(worst <= MPPI_TARGET_MS)})."]
    return "\n".join(out)


def render_metrics(r: dict[str, Any]) -> str:
    out = [machine_line(r["machine"], r["load_end"], "python benchmarks/bench_metrics.py"),
           f"`pathfuse.metrics.evaluate()` (length, clearance, smoothness, collision check of a "
           f"path) on the paths of the paper's five planners on {r['seeds']} paper maps, "
           "against the k-d tree version it replaced (`old`, kept in the benchmark) and "
           "shapely's `LineString.distance` to the union of the obstacle squares (clearance "
           "only; the union built beforehand); wall time per call, median over the cases.", "",
           "| paths | cases | `evaluate()` | old `evaluate()` | old / new | `min_clearance` | "
           "shapely |", "|---|---|---|---|---|---|---|"]

    def row(s: dict[str, Any], label: str) -> str:
        sh = f"{ms(s['shapely']['wall_ms'])}" if "shapely" in s else "n/a"
        return (f"| {label} | {s['cases']} | {ms(s['new']['wall_ms'])} | "
                f"{ms(s['old']['wall_ms'])} | {ratio(s['old/new'])}× | "
                f"{ms(s['new_clr']['wall_ms'])} | {sh} |")

    for s in r["paper"]:
        out.append(row(s, "paper maps, all planners" if s["label"] == "all" else
                       f"paper maps, {s['label']}"))
    for s in r["large"]:
        out.append(row(s, f"{s['map']}: {s['points']}-point path"))
    c = r["checks"]
    out += ["", f"The new and the old code agree on all {c['cases']} cases "
            f"({c['identical']} bit for bit)."]
    if r.get("shapely_union_ms") is not None:
        out[-1] += (f" shapely's union of a paper map's squares costs {ms(r['shapely_union_ms'])}"
                    " once per map (not in the table).")
    return "\n".join(out)


def render_anyangle(r: dict[str, Any]) -> str:
    out = [machine_line(r["machine"], r["load_end"], "python benchmarks/bench_anyangle.py"),
           "Scenario lines of MovingAI maps through `plan()`, the planners interleaved query by "
           "query; CPU time per query, median, and its ratio to A*'s; each path's length over "
           "A*'s, median; paths checked collision-free by `pathfuse.metrics`. numba "
           "compilation and A*'s per-map buffers are made before the clock starts.", "",
           "| map | planner | CPU per query | / A* | length / A* | collision-free |",
           "|---|---|---|---|---|---|"]
    for x in r.get("part1", []):
        out.append(f"| {x['map']} | {x['planner']} | {ms(x['cpu_ms'])} | "
                   f"{ratio(x['cpu_over_astar'])} | {x['length_over_astar']:.3f} | "
                   f"{x['collision_free']}/{x['queries']} |")
    p2 = r.get("part2")
    if p2:
        out += ["", f"`shortest` (the true shortest path: a visibility graph of the convex "
                f"corners) on {p2['paper_maps']} paper maps, its corner extraction included; "
                "CPU time per query, median, and each planner's length over the shortest, "
                "mean:", "", "| planner | CPU per query | / A* | over the shortest |",
                "|---|---|---|---|"]
        for x in p2["paper"]:
            out.append(f"| {x['planner']} | {ms(x['cpu_ms'])} | {ratio(x['cpu_over_astar'])} | "
                       f"{100 * x['excess_over_shortest']:+.2f} % |")
        maps = list(dict.fromkeys(x["map"] for x in p2["big"]))
        if maps:
            out += ["", "On 512 × 512 maps, a few of each map's 50 longest scenario lines:", "",
                    "| map | convex corners | queries | `shortest` CPU per query | A* CPU per "
                    "query | length / A* |", "|---|---|---|---|---|---|"]
            for m in maps:
                xs = [x for x in p2["big"] if x["map"] == m]
                c = sorted(x["cpu_s"] for x in xs)
                a = sorted(x["astar_cpu_ms"] for x in xs)
                lr = sorted(x["length_over_astar"] for x in xs)
                out.append(f"| {m} | {xs[0]['corners']} | {len(xs)} | "
                           f"{c[0]:.3f}–{c[-1]:.3f} s | {ms(a[0])}–{ms(a[-1])} | "
                           f"{lr[0]:.3f}–{lr[-1]:.3f} |")
    return "\n".join(out)


BENCHMARK = {"search": "bench_search", "peers": "bench_astar", "plan": "bench_plan",
             "startup": "bench_startup", "stepping": "bench_stepping",
             "controllers": "bench_controllers", "shield": "bench_shield", "mppi": "bench_mppi",
             "metrics": "bench_metrics", "anyangle": "bench_anyangle"}
"""The benchmark script (in ``benchmarks/``) whose JSON makes each block."""

RENDER: dict[str, Callable[[dict[str, Any]], str]] = {
    "search": render_search, "peers": render_peers, "plan": render_plan, "startup": render_startup,
    "stepping": render_stepping, "controllers": render_controllers, "shield": render_shield,
    "mppi": render_mppi, "metrics": render_metrics, "anyangle": render_anyangle}


def render(name: str) -> str:
    """The Markdown of block ``name`` from ``benchmarks/results/NAME.json``."""
    return RENDER[name](json.loads((RESULTS / f"{name}.json").read_text()))


def _pattern(name: str) -> re.Pattern[str]:
    return re.compile(rf"(<!-- speed:{name} begin[^\n]*-->\n)(.*?)(\n<!-- speed:{name} end -->)",
                      re.S)


def blocks_in(text: str) -> dict[str, str]:
    """The generated blocks of a page's text, by name."""
    out = {}
    for name in BLOCKS:
        m = _pattern(name).search(text)
        if m:
            out[name] = m.group(2)
    return out


def rewrite(text: str, names: list[str]) -> str:
    for name in names:
        pat = _pattern(name)
        if not pat.search(text):
            raise SystemExit(f"{SPEED_PAGE.name} has no block speed:{name}")
        body = render(name)
        text = pat.sub(lambda m, body=body: m.group(1) + body + m.group(3), text)
    return text


def commit() -> str | None:
    """The commit measured (``-dirty`` when the work tree differs from it), if in git."""
    import subprocess

    try:
        rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, check=True,
                             capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "src"],
                               cwd=ROOT, check=True, capture_output=True, text=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return None
    return rev + ("-dirty" if dirty.strip() else "")


def run(name: str) -> None:
    """Run the benchmark of block ``name``, its JSON into benchmarks/results/ (with the commit
    of ``src/`` measured)."""
    sys.path.insert(0, str(HERE))
    RESULTS.mkdir(exist_ok=True)
    out = str(RESULTS / f"{name}.json")
    print(f"\n==== {name}", flush=True)
    rev = commit()
    import importlib

    importlib.import_module(BENCHMARK[name]).main(["--json", out])
    if rev:
        data = json.loads(Path(out).read_text())
        data.setdefault("machine", {})["commit"] = rev
        Path(out).write_text(json.dumps(data, indent=2))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="+", choices=BLOCKS, default=list(BLOCKS))
    ap.add_argument("--no-run", action="store_true", help="only rewrite docs/speed.md")
    ap.add_argument("--check", action="store_true",
                    help="exit 1 when a block of docs/speed.md differs from its JSON")
    args = ap.parse_args(argv)
    text = SPEED_PAGE.read_text()
    if args.check:
        bad = [n for n, body in blocks_in(text).items() if body != render(n)]
        print("stale blocks: " + ", ".join(bad) if bad else "every block is up to date")
        return 1 if bad else 0
    if not args.no_run:
        for name in args.only:
            run(name)
    SPEED_PAGE.write_text(rewrite(SPEED_PAGE.read_text(), args.only))
    print(f"\nrewrote the blocks {', '.join(args.only)} of {SPEED_PAGE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
