"""The ``pathfuse`` command line.  Thin: parses arguments and calls the library.

Every error a user can cause ends in one line on stderr and a non-zero exit
status (2 for bad input, 1 for a failed check such as a scen mismatch or a
plan that did not succeed), never a traceback.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from pathfuse.result import PathfuseError

EXIT_FAIL = 1
EXIT_USAGE = 2


class CliError(PathfuseError):
    """A bad command-line value (exit status 2)."""


def _fmt(s: str) -> str:
    return s.strip("\n")


MAIN_EPILOG = _fmt("""
examples:
  pathfuse paper --seeds 100 --out paper-out
  pathfuse plan --map paper --seed 3 --plot plan.png
  pathfuse plan --map den312d.map --start 10.5,70.5 --goal 60.5,8.5 --json
  pathfuse scen maze512-4-6.map maze512-4-6.map.scen --limit 500
  pathfuse simulate examples/scenarios/head_on.yaml --planner astar --gif head_on.gif
  pathfuse dynamic --seeds 50 --moving 0 2 4 8 --out dynamic-out
  pathfuse bench experiments/fusion-sweep-r1-r2-step.yaml --db sweep.db --seeds 20
  pathfuse report sweep.db --out sweep-report
  pathfuse planners

Run 'pathfuse COMMAND --help' for the options of a command.
""")


# --------------------------------------------------------------------------- parsing helpers
def parse_point(text: str, what: str) -> tuple[float, float]:
    """``"1.5,2"`` -> (1.5, 2.0); :class:`CliError` naming ``what`` otherwise."""
    parts = [p.strip() for p in str(text).replace(";", ",").split(",")]
    try:
        if len(parts) != 2:
            raise ValueError
        x, y = float(parts[0]), float(parts[1])
    except ValueError:
        raise CliError(f"{what}: expected X,Y (two numbers in metres), got {text!r}") from None
    if not (np.isfinite(x) and np.isfinite(y)):
        raise CliError(f"{what}: coordinates must be finite, got {text!r}")
    return x, y


def parse_params(items: Sequence[str] | None) -> dict[str, Any]:
    """``["r1=1.5", "ahead=paper-x"]`` -> {"r1": 1.5, "ahead": "paper-x"} (YAML scalars)."""
    import yaml

    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, val = item.partition("=")
        if not sep or not key.strip():
            raise CliError(f"--param: expected KEY=VALUE, got {item!r}")
        try:
            out[key.strip()] = yaml.safe_load(val)
        except yaml.YAMLError:
            raise CliError(f"--param {key}: cannot read value {val!r}") from None
    return out


def _int_at_least(minimum: int, what: str):
    """An argparse type: an integer >= ``minimum`` (``what`` names it in the error)."""

    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            v = minimum - 1
        if v < minimum:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
        return v

    return parse


_positive_int = _int_at_least(1, "a positive integer")
_nonneg_int = _int_at_least(0, "an integer >= 0")


def _float(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not np.isfinite(v):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return v


def _nonneg_float(text: str) -> float:
    v = _float(text)
    if v < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return v


def _positive_float(text: str) -> float:
    v = _float(text)
    if v <= 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return v


def parse_speed(text: str) -> tuple[float, float]:
    """``"0.3,0.8"`` -> (0.3, 0.8); one number ``V`` means ``V,V``; :class:`CliError` otherwise.

    >>> parse_speed("0.3,0.8"), parse_speed("0.5")
    ((0.3, 0.8), (0.5, 0.5))
    """
    parts = [p.strip() for p in str(text).split(",")]
    try:
        if len(parts) not in (1, 2):
            raise ValueError
        lo, hi = float(parts[0]), float(parts[-1])
        if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo <= hi):
            raise ValueError
    except ValueError:
        raise CliError(f"--speed: expected MIN,MAX in m/s with 0 < MIN <= MAX, "
                       f"got {text!r}") from None
    return lo, hi


def parse_planner_list(text: str | None) -> tuple[str, ...]:
    """``"fusion, astar"`` -> ("fusion", "astar"); None -> () (all planners)."""
    if text is None:
        return ()
    names = tuple(n.strip() for n in str(text).split(",") if n.strip())
    if not names:
        raise CliError(f"--planners: expected comma-separated online planner names, "
                       f"got {text!r}")
    return names


def parse_planner_params(items: Sequence[str] | None) -> dict[str, dict[str, Any]]:
    """``["fusion.repulsion=velocity"]`` -> {"fusion": {"repulsion": "velocity"}}."""
    out: dict[str, dict[str, Any]] = {}
    for key, val in parse_params(items).items():
        name, dot, param = key.partition(".")
        if not dot or not name or not param:
            raise CliError(f"--param: expected PLANNER.KEY=VALUE, got {key!r}")
        out.setdefault(name, {})[param] = val
    return out


class _Parser(argparse.ArgumentParser):
    """argparse that reports errors in one line and exits with status 2."""

    def error(self, message: str):  # type: ignore[override]
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message}\n")


def _load_map(args: argparse.Namespace):
    from pathfuse.io import load_map

    return load_map(args.map, resolution=args.resolution, seed=args.seed)


# --------------------------------------------------------------------------- commands
def cmd_plan(args: argparse.Namespace) -> int:
    import pathfuse
    from pathfuse.generate import PAPER_GOAL, PAPER_START

    grid = _load_map(args)
    is_paper = str(args.map).lower() == "paper"
    if args.start is None or args.goal is None:
        if not is_paper:
            raise CliError("--start and --goal are required unless --map paper")
    start = parse_point(args.start, "--start") if args.start else PAPER_START
    goal = parse_point(args.goal, "--goal") if args.goal else PAPER_GOAL
    params = parse_params(args.param)
    budget = pathfuse.Budget(time_limit_s=args.time_limit) if args.time_limit else None
    _warm_with_notice(args.planner)
    result = pathfuse.plan(grid, start, goal, planner=args.planner, budget=budget,
                           robot_radius_m=args.robot_radius, **params)
    if args.plot:
        from pathfuse.viz import plot_plan

        plot_plan(
            grid, result, start, goal, args.plot,
            title=f"{grid.name}: {args.planner} {result.status.name} {result.length:.3f} m",
            astar_points=result.info.get("astar_path"),
        )
    if args.json:
        d = result.to_dict()
        d["map"] = grid.name
        d["start"], d["goal"] = list(start), list(goal)
        print(json.dumps(d))
    else:
        print(f"map       {grid.name}  ({grid.width} x {grid.height} cells, {grid.resolution:g} m)")
        print(f"planner   {result.planner}")
        print(f"status    {result.status.name}  {result.message}")
        print(f"length    {result.length:.4f} m  ({len(result.path)} points)")
        print(f"time      {result.time_s * 1e3:.3f} ms")
        if result.expansions:
            print(f"expanded  {result.expansions}")
        if result.iterations:
            print(f"steps     {result.iterations}")
        if args.plot:
            print(f"figure    {args.plot}")
    return 0 if result.success else EXIT_FAIL


def cmd_scen(args: argparse.Namespace) -> int:
    import pathfuse
    from pathfuse.io import read_movingai, read_scen

    grid = read_movingai(args.map)
    problems = read_scen(args.scen, grid)
    if args.limit:
        problems = problems[: args.limit]
    n_ok = n_bad = 0
    total_t = 0.0
    worst: list[str] = []
    for p in problems:
        r = pathfuse.plan(grid, p.start, p.goal, planner="astar", heuristic=args.heuristic)
        total_t += r.time_s
        ok = r.success and abs(r.length - p.optimal_length) <= args.tol * max(1.0, p.optimal_length)
        if ok:
            n_ok += 1
        else:
            n_bad += 1
            if len(worst) < 10:
                worst.append(
                    f"  line {p.line}: expected {p.optimal_length:.8f}, got "
                    f"{r.length:.8f} ({r.status.name})"
                )
    n = n_ok + n_bad
    print(f"{Path(args.scen).name}: {n_ok}/{n} lines match the optimal length "
          f"(rel. tol {args.tol:g}); A* time {total_t:.3f} s, "
          f"{1e3 * total_t / max(n, 1):.3f} ms/query")
    for line in worst:
        print(line)
    return 0 if n_bad == 0 else EXIT_FAIL


def _warm_with_notice(planner: str) -> None:
    """Compile the planner's kernels now, saying so first when numba's cache is cold."""
    from pathfuse.planners.registry import get_planner
    from pathfuse.planners.run import warm

    def notice() -> None:
        print("pathfuse: compiling planner kernels (first run only; cached afterwards)",
              file=sys.stderr, flush=True)

    warm(get_planner(planner), notify=notice)


def planner_table() -> dict[str, Any]:
    """Every registered planner as JSON-ready data (what ``pathfuse planners --json`` prints)."""
    import dataclasses

    from pathfuse.planners.registry import REGISTRY, planner_names
    from pathfuse.validate import param_spec

    out: dict[str, Any] = {}
    for n in planner_names():
        spec = REGISTRY[n]
        params = []
        for f in dataclasses.fields(spec.params_cls):
            ps = param_spec(f)
            default = getattr(spec.params_cls(), f.name)
            params.append({
                "name": f.name, "default": default,
                "kind": ps.kind if ps else "", "unit": ps.unit if ps else "",
                "accepts": ps.describe() if ps else "", "help": ps.help if ps else "",
            })
        ctrl = getattr(spec.controller, "label", "") if spec.controller else ""
        out[n] = {"description": spec.description, "offline": spec.offline,
                  "online": spec.online, "global_planner": spec.global_planner,
                  "controller": ctrl or None, "aliases": list(spec.aliases),
                  "params": params}
    return out


def cmd_planners(args: argparse.Namespace) -> int:
    table = planner_table()
    if args.json:
        print(json.dumps(table))
        return 0
    for name, d in table.items():
        runs = " and ".join(k for k in ("offline", "online") if d[k])
        also = f"; also called {', '.join(d['aliases'])}" if d["aliases"] else ""
        parts = ["global planner: A*" if d["global_planner"] == "astar" else "",
                 f"controller: {d['controller']}" if d["controller"] else "a plug-in function"]
        print(f"{name}  ({'; '.join(x for x in parts if x)}; runs {runs}{also})")
        print(f"  {d['description']}")
        if args.params:
            for p in d["params"]:
                unit = f" {p['unit']}" if p["unit"] and p["default"] is not None else ""
                print(f"    {p['name']} = {p['default']!r}{unit}  ({p['accepts']}): {p['help']}")
        else:
            shown = ", ".join(f"{p['name']}={p['default']!r}" for p in d["params"])
            print(f"  parameters: {shown}")
    if not args.params:
        print("\n'pathfuse planners --params' explains every parameter (unit, range, meaning).")
    return 0


def _study_db(out: str) -> Path:
    """The result store of a preset study: ``OUT/study.db`` (the folder is created)."""
    folder = Path(out).expanduser()
    if folder.exists() and not folder.is_dir():
        raise CliError(f"--out: {folder} exists and is not a folder")
    folder.mkdir(parents=True, exist_ok=True)
    return folder / "study.db"


def cmd_paper(args: argparse.Namespace) -> int:
    from pathfuse.studies.paper import PaperConfig, run_paper, summary_rows, write_paper_outputs

    cfg = PaperConfig(
        n_seeds=args.seeds, first_seed=args.first_seed,
        figure_seed=args.seed if args.seed is not None else args.first_seed,
        step_m=args.step,
    )
    if not cfg.first_seed <= cfg.figure_seed < cfg.first_seed + cfg.n_seeds:
        raise CliError(
            f"--seed {cfg.figure_seed} is not among the maps run "
            f"({cfg.first_seed}..{cfg.first_seed + cfg.n_seeds - 1})"
        )
    for name in cfg.planners:
        _warm_with_notice(name)
    run = run_paper(cfg, progress=False if args.quiet else None, workers=args.workers,
                    db_path=_study_db(args.out))
    files = write_paper_outputs(run, args.out)
    n_runs = len(run.records)
    sm = run.summary
    print(f"{n_runs} runs on {cfg.n_seeds} maps: {sm.ran} run now in {run.wall_s:.2f} s "
          f"({sm.runs_per_s:.0f} runs/s, {sm.workers} worker{'s' if sm.workers != 1 else ''})"
          + (f", {sm.skipped} already in {sm.db_path}" if sm.skipped else ""))
    print(f"{'planner':<8} {'success':>12} {'length mean':>12} {'R_length':>10} {'time mean':>11}")
    for r in summary_rows(run):
        rl = "-" if r["planner"] == "fusion" else f"{100 * r['r_length_mean']:+.2f}%"
        print(f"{r['planner']:<8} {r['successes']:>5}/{r['maps']:<6} "
              f"{r['length_mean_m']:>11.4f}m {rl:>10} {1e3 * r['time_mean_s']:>9.3f}ms")
    for path in files.values():
        print(f"wrote {path}")
    return 0


def cmd_simulate(args: argparse.Namespace) -> int:
    from pathfuse.world import load_scenario, simulate

    out = args.gif or args.mp4
    fmt = "gif" if args.gif else "mp4" if args.mp4 else None
    if out is not None:
        from pathfuse.viz.animate import animate_episode, require_ffmpeg

        if fmt == "mp4":
            require_ffmpeg()  # before simulating: fail fast, in one line
        parent = Path(out).expanduser().resolve().parent
        if not parent.is_dir():
            raise CliError(f"--{fmt}: the folder {parent} does not exist")
    sc = load_scenario(args.scenario)
    params = parse_params(args.param)
    if args.planner is None or args.planner == sc.planner.name:
        # the scenario's own planner keeps the scenario's parameters (--param overrides them)
        choice = {"name": args.planner or sc.planner.name,
                  "params": {**dict(sc.planner.params), **params}}
    else:
        choice = {"name": args.planner, "params": params}
    ep = simulate(sc, planner=choice, seed=args.seed)
    anim = None
    if out is not None:
        anim = animate_episode(ep, out, format=fmt, fps=args.fps, frame_step=args.frame_step)
    if args.json:
        d = ep.to_dict(trajectories=args.trajectories)
        d["scenario_file"] = str(args.scenario)
        if anim is not None:
            d["animation"] = {"path": str(anim.path), "format": anim.format,
                              "frames": anim.n_frames, "frame_step": anim.frame_step,
                              "fps": anim.fps, "size_px": list(anim.size_px)}
        print(json.dumps(d))
    else:
        dt = ep.scenario.dt
        k = len(ep.obstacle_radii)
        grid = ep.grid
        print(f"scenario  {sc.name}  ({grid.width} x {grid.height} cells of {grid.resolution:g} m, "
              f"{k} moving obstacle{'s' if k != 1 else ''})")
        print(f"planner   {ep.planner}")
        print(f"status    {ep.status.name}  {ep.message}")
        ttg = "-" if ep.time_to_goal_s is None else f"{ep.time_to_goal_s:.2f} s"
        print(f"to goal   {ttg}  ({ep.n_ticks} ticks of {dt:g} s, "
              f"{ep.times[-1]:.2f} s simulated)")
        print(f"path      {ep.path_length_m:.3f} m")

        def gap(v: float) -> str:
            return "-" if not np.isfinite(v) else f"{v:.3f} m"

        print(f"distance  {gap(ep.min_distance_m)} min to any obstacle  (moving: "
              f"{gap(ep.min_obstacle_distance_m)}, static: {gap(ep.min_static_clearance_m)})")
        print(f"planning  {1e6 * ep.mean_plan_time_s:.1f} us/tick mean, "
              f"{1e3 * ep.setup_time_s:.2f} ms setup")
        if anim is not None:
            print(f"animation {anim.path}  ({anim.n_frames} frames, every {anim.frame_step} "
                  f"tick{'s' if anim.frame_step != 1 else ''}, {anim.fps:g} fps = "
                  f"{anim.speedup(dt):g}x real time, {anim.render_s:.2f} s to write)")
    return 0 if ep.reached else EXIT_FAIL


def cmd_dynamic(args: argparse.Namespace) -> int:
    from pathfuse.studies.dynamic import (
        DynamicConfig,
        run_dynamic,
        success_pivot,
        summary_rows,
        write_dynamic_outputs,
    )

    cfg = DynamicConfig(
        n_seeds=args.seeds, moving=tuple(args.moving), speed_range=parse_speed(args.speed),
        planners=parse_planner_list(args.planners), seed=args.seed,
        params=parse_planner_params(args.param),
    )
    for name in cfg.planners:
        _warm_with_notice(name)
    run = run_dynamic(cfg, progress=False if args.quiet else None, workers=args.workers,
                      db_path=_study_db(args.out))
    files = write_dynamic_outputs(run, args.out)
    print(f"{len(run.records)} episodes ({len(cfg.planners)} planners x {len(cfg.moving)} disc "
          f"counts x {cfg.n_seeds} scenarios) in {run.wall_s:.2f} s "
          f"({run.episodes_per_s:.1f} episodes/s, {run.workers} worker"
          f"{'s' if run.workers != 1 else ''})")
    rows = summary_rows(run)
    for title, key in (("success rate [95% CI]", "reached"),
                       ("collision rate [95% CI]", "collision")):
        table = success_pivot(rows, key)
        widths = [max(len(r[i]) for r in table) for i in range(len(table[0]))]
        print(f"\n{title}")
        for r in table:
            print("  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip())
    print()
    for path in files.values():
        print(f"wrote {path}")
    return 0


def parse_seeds(text: str) -> int | str | list[int]:
    """``--seeds`` of ``pathfuse bench``: ``"20"`` (seeds 0..19), ``"100:200"`` or ``"3,7,9"``.

    >>> parse_seeds("20"), parse_seeds("5:8"), parse_seeds("3, 7")
    (20, '5:8', [3, 7])
    """
    t = str(text).strip()
    try:
        if ":" in t:
            a, b = (int(x) for x in t.split(":"))
            if not 0 <= a < b:
                raise ValueError
            return f"{a}:{b}"
        if "," in t:
            vals = [int(x) for x in t.split(",") if x.strip()]
            if not vals or min(vals) < 0:
                raise ValueError
            return vals
        n = int(t)
        if n < 1:
            raise ValueError
        return n
    except ValueError:
        raise CliError(f"--seeds: expected a count N >= 1, a range A:B with 0 <= A < B, "
                       f"or a list A,B,C of seeds >= 0, got {text!r}") from None


def cmd_bench(args: argparse.Namespace) -> int:
    from pathfuse.bench import SweepInterrupted, run_bench

    seeds = None if args.seeds is None else parse_seeds(args.seeds)
    try:
        summary = run_bench(args.experiment, args.db, seeds=seeds, workers=args.workers,
                            scheduler=args.scheduler,
                            progress=False if args.no_progress else None,
                            retry_errors=args.retry_errors, batch_size=args.batch_size)
    except SweepInterrupted as exc:
        print(exc.summary, flush=True)
        print("pathfuse bench: interrupted; run the same command again to resume",
              file=sys.stderr)
        return 130
    print(summary)
    return 0 if summary.errors == 0 else EXIT_FAIL


def cmd_report(args: argparse.Namespace) -> int:
    from pathfuse.bench.report import build_report

    report = build_report(args.db, reference=args.reference, params=args.param)
    files = report.write(args.out, embed_images=not args.link_images)
    study, rows = report.study, report.rows
    pooled = {r["scope"] for r in rows if r["pooled"]}
    shown = [r for r in rows if r["scope"] in pooled]
    n_exp, n_cfg = len({r["experimentid"] for r in study.runs}), len(study.config_ids())
    print(f"{args.db}: {len(study.runs)} runs, {n_exp} map entr{'y' if n_exp == 1 else 'ies'}, "
          f"{n_cfg} planner configuration{'' if n_cfg == 1 else 's'}")
    head = ("scope", "configuration", "runs", "success", "errors", "length mean", "R_length")
    table = [head]
    for r in shown:
        rl = "n/a" if not r["r_length_pairs"] else \
            f"{100 * r['r_length_mean']:+.2f}% (n={r['r_length_pairs']})"
        lm = "n/a" if not r["length_n"] else f"{r['length_mean_m']:.3f} m"
        table.append((r["scope"], r["config"], str(r["runs"]),
                      f"{100 * r['success_rate']:.1f}%", str(r["errors"]), lm, rl))
    widths = [max(len(row[i]) for row in table) for i in range(len(head))]
    for row in table:
        print("  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip())
    print(f"wrote {len(files)} files into {args.out}: report.html, report.md, summary.csv, "
          "parameters.csv and the figures")
    return 0


# --------------------------------------------------------------------------- parser
def build_parser() -> argparse.ArgumentParser:
    from pathfuse import __version__

    parser = _Parser(
        prog="pathfuse",
        description="2-D robot path planning: exact fast A*, artificial potential fields and "
        "the A*-APF fusion planner of Ju, Luo and Yan.",
        epilog=MAIN_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"pathfuse {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    p = sub.add_parser(
        "plan",
        help="plan one path on a map and print (or plot) the result",
        description="Plan one path on a map.  Coordinates are world coordinates in metres "
        "(ROS convention: origin = lower-left corner of cell (0, 0)).",
        epilog=_fmt("""
examples:
  pathfuse plan --map paper --seed 3 --planner astar --plot plan.png
  pathfuse plan --map maps/office.yaml --start 1.0,2.5 --goal 8.2,4.0 --robot-radius 0.2
  pathfuse plan --map room.png --resolution 0.05 --start 1,1 --goal 5,4 --json
  pathfuse plan --map paper --planner astar --param heuristic=octile

--map accepts: 'paper' (the paper's random 15 m map, --seed N), a MovingAI .map,
a ROS map_server .yaml, an inline-rows .yaml, or a .png/.pgm/.npy (with --resolution).
"""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--map", required=True, help="map file, or 'paper'")
    p.add_argument("--start", help="start X,Y in metres (default for --map paper: 1,1)")
    p.add_argument("--goal", help="goal X,Y in metres (default for --map paper: 11,11)")
    p.add_argument("--planner", default="astar", help="planner name (see 'pathfuse planners')")
    p.add_argument("--param", action="append", metavar="KEY=VALUE",
                   help="planner parameter, repeatable (e.g. --param heuristic=octile)")
    p.add_argument("--resolution", type=_float, help="metres per cell for image/.npy maps")
    p.add_argument("--seed", type=int, default=0, help="seed of --map paper (default 0)")
    p.add_argument("--robot-radius", type=_nonneg_float, default=0.0,
                   help="radius of a disc robot in metres: the path keeps this clearance "
                   "from obstacles and the map's edge (default 0)")
    p.add_argument("--time-limit", type=_float, help="planning time limit in seconds")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="OUT.png", help="write a PNG figure of the plan")
    p.set_defaults(func=cmd_plan)

    s = sub.add_parser(
        "scen",
        help="check A* against a MovingAI scenario file's optimal lengths",
        description="Run the lines of a MovingAI .scen file through A* (8-connected, sqrt(2) "
        "diagonals, no corner cutting) and count how many match the file's optimal length.  "
        "Exit status 1 on any mismatch.",
        epilog=_fmt("""
example:
  pathfuse scen den312d.map den312d.map.scen
  pathfuse scen maze512-4-6.map maze512-4-6.map.scen --limit 1000 --heuristic octile
"""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    s.add_argument("map", help="MovingAI .map file")
    s.add_argument("scen", help="MovingAI .scen file for that map")
    s.add_argument("--limit", type=_positive_int, help="check only the first N lines")
    s.add_argument("--heuristic", default="octile", choices=["octile", "euclidean"],
                   help="A* heuristic (default octile; both are exact)")
    s.add_argument("--tol", type=_float, default=1e-6, help="relative tolerance (default 1e-6)")
    s.set_defaults(func=cmd_scen)

    pp = sub.add_parser(
        "paper",
        help="reproduce the paper's Tables I and II and Fig. 3 over many seeded maps",
        description="Run the paper's setup (15 m map, start (1, 1), goal (11, 11), 50 random "
        "obstacles, K_att 40, K_rep 5, rho_0 2 m) with all five planners on N seeded maps and "
        "write Tables I and II (one map and statistics over all maps) as Markdown and CSV, "
        "Fig. 3 and a box plot of R_length into --out.",
        epilog=_fmt("""
examples:
  pathfuse paper --out paper-out
  pathfuse paper --seeds 1000 --seed 7 --out paper-1000
"""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    pp.add_argument("--seeds", type=_positive_int, default=100,
                    help="number of maps (default 100)")
    pp.add_argument("--first-seed", type=int, default=0, help="seed of the first map (default 0)")
    pp.add_argument("--seed", type=int, default=None,
                    help="the map of the one-map tables and Fig. 3 (default: the first seed)")
    pp.add_argument("--step", type=_float, default=0.1,
                    help="step length in metres of every stepping planner (default 0.1)")
    pp.add_argument("--workers", type=_positive_int, default=None,
                    help="worker processes (default: every usable CPU; 1 = in this process)")
    pp.add_argument("--out", default="paper-out",
                    help="output folder (default paper-out); its study.db keeps every run, "
                    "so running the same command again resumes or reuses them")
    pp.add_argument("--quiet", action="store_true",
                    help="no progress bar (default: a bar on stderr when it is a terminal)")
    pp.set_defaults(func=cmd_paper)

    sm = sub.add_parser(
        "simulate",
        help="run one episode of a moving-obstacle scenario (and animate it)",
        description="Run one episode of a dynamic scenario file (map, robot, moving discs, "
        "planner; see examples/scenarios/crossing.yaml) with an online planner and print "
        "its outcome: status, time to goal, path length, least distance to obstacles, ticks "
        "and planning time.  Exit status 0 when the robot reached the goal, 1 otherwise "
        "(collision, timeout, local minimum, no path).",
        epilog=_fmt("""
examples:
  pathfuse simulate examples/scenarios/head_on.yaml
  pathfuse simulate examples/scenarios/head_on.yaml --planner astar --gif head_on.gif
  pathfuse simulate examples/scenarios/crossing.yaml --planner fusion --param repulsion=velocity
  pathfuse simulate examples/scenarios/random_walkers.yaml --seed 4 --json
  pathfuse simulate examples/scenarios/crossing.yaml --mp4 crossing.mp4 --fps 20 --frame-step 1

Every planner of 'pathfuse planners' runs online (default: the scenario's planner).
GIFs are written with pillow; MP4 needs ffmpeg on PATH.  By default
an animation plays in real time unless that takes more than 150 frames, then faster;
--frame-step 1 draws every tick.
"""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sm.add_argument("scenario", help="scenario YAML file")
    sm.add_argument("--planner", help="planner (default: the scenario's)")
    sm.add_argument("--param", action="append", metavar="KEY=VALUE",
                    help="planner parameter, repeatable (e.g. --param repulsion=velocity)")
    sm.add_argument("--seed", type=_nonneg_int, default=None,
                    help="episode seed for random walks (default: the scenario's)")
    anim = sm.add_mutually_exclusive_group()
    anim.add_argument("--gif", metavar="OUT.gif", help="write an animated GIF")
    anim.add_argument("--mp4", metavar="OUT.mp4", help="write an MP4 video (needs ffmpeg)")
    sm.add_argument("--fps", type=_positive_float, default=10.0,
                    help="animation frames per second (default 10)")
    sm.add_argument("--frame-step", type=_positive_int, default=None,
                    help="ticks per animation frame (default: real time, at most ~150 frames)")
    sm.add_argument("--json", action="store_true", help="print one JSON object")
    sm.add_argument("--trajectories", action="store_true",
                    help="with --json: include the per-tick positions and the path")
    sm.set_defaults(func=cmd_simulate)

    dy = sub.add_parser(
        "dynamic",
        help="benchmark the online planners among moving obstacles",
        description="Run every online planner (or --planners) on the same N generated "
        "scenarios per number of moving discs (paper map family, start (1, 1), goal (11, 11), "
        "discs aimed across the route; deterministic in --seed) and write, into --out: "
        "dynamic.md (success, collision, timeout and local-minimum rates with 95% Wilson "
        "intervals, path length and time to goal over the successful episodes, a paired "
        "comparison with the fusion), summary.csv, episodes.csv (one row per episode, nothing "
        "dropped), paired.csv and success_vs_moving.png.  The defaults (1200 episodes) take "
        "about 15 s on one core.",
        epilog=_fmt("""
examples:
  pathfuse dynamic
  pathfuse dynamic --seeds 50 --moving 0 2 4 8 --out dynamic-out
  pathfuse dynamic --seeds 100 --moving 0 4 8 12 --speed 0.5,1.0 --planners fusion,astar-replan
  pathfuse dynamic --seeds 200 --workers 2 --param fusion.repulsion=velocity --out velocity
"""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    dy.add_argument("--seeds", type=_positive_int, default=50,
                    help="scenarios per number of moving discs (default 50)")
    dy.add_argument("--moving", type=_nonneg_int, nargs="+", default=[0, 2, 4, 8],
                    metavar="K", help="numbers of moving discs (default: 0 2 4 8)")
    dy.add_argument("--speed", default="0.3,0.8", metavar="MIN,MAX",
                    help="disc speeds are drawn from [MIN, MAX] m/s (default 0.3,0.8)")
    dy.add_argument("--planners", metavar="A,B,...",
                    help="online planners, comma-separated (default: all registered)")
    dy.add_argument("--param", action="append", metavar="PLANNER.KEY=VALUE",
                    help="planner parameter, repeatable (e.g. --param fusion.swerve=0)")
    dy.add_argument("--seed", type=_nonneg_int, default=0,
                    help="master seed of the scenario family (default 0)")
    dy.add_argument("--workers", type=_positive_int, default=None,
                    help="worker processes (default: every usable CPU; 1 = in this process)")
    dy.add_argument("--out", default="dynamic-out",
                    help="output folder (default dynamic-out); its study.db keeps every "
                    "episode, so running the same command again resumes or reuses them")
    dy.add_argument("--quiet", action="store_true",
                    help="no progress bar (default: a bar on stderr when it is a terminal)")
    dy.set_defaults(func=cmd_dynamic)

    b = sub.add_parser(
        "bench",
        help="run (or resume) a benchmark sweep into a study database",
        description="Run every run of an experiment file (maps x seeds x queries x planners "
        "x parameter combinations) and store each in an SQLite study database in OMPL's "
        "benchmark layout.  Runs already stored are skipped, so running the same command "
        "again resumes an interrupted sweep.  Exit status 0 when no run raised, 1 when some "
        "did (they are stored as ERROR with their traceback), 2 for a bad experiment file "
        "or argument, 130 when interrupted (Ctrl-C; what finished is stored).",
        epilog=_fmt("""
examples:
  pathfuse bench experiments/paper-static-1000-seeds.yaml --db paper.db
  pathfuse bench experiments/fusion-sweep-r1-r2-step.yaml --db sweep.db --seeds 20
  pathfuse bench experiments/fusion-sweep-r1-r2-step.yaml --db sweep.db --seeds 100:200
  pathfuse bench experiments/dynamic-benchmark.yaml --db dyn.db --workers 1 --no-progress
  pathfuse bench experiments/movingai-maps.yaml --db mai.db --scheduler tcp://10.0.0.5:8786
  pathfuse report sweep.db --out sweep-report

See experiments/*.yaml for the file format (maps, seeds, planners, swept parameters).
"""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    b.add_argument("experiment", help="experiment YAML file")
    b.add_argument("--db", required=True, metavar="STUDY.db",
                   help="SQLite study database (created if missing, resumed if not)")
    b.add_argument("--seeds", metavar="N|A:B|A,B,..",
                   help="override every seed list of the file: N (seeds 0..N-1), a range "
                   "A:B or a list")
    b.add_argument("--workers", type=_positive_int, default=None,
                   help="local worker processes (default: every usable CPU; 1 = in this "
                   "process)")
    b.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                   help="run on a Dask distributed cluster (pip install 'pathfuse[dask]')")
    b.add_argument("--batch-size", type=_positive_int, default=None,
                   help="runs per task (default: about 8 tasks per worker, at most 64)")
    b.add_argument("--retry-errors", action="store_true",
                   help="run again the runs stored as ERROR")
    b.add_argument("--no-progress", action="store_true",
                   help="no progress bar (default: a bar on stderr when it is a terminal)")
    b.set_defaults(func=cmd_bench)

    r = sub.add_parser(
        "report",
        help="tables and figures of a study database (Markdown, CSV, PNG, HTML)",
        description="Summarise a study database of 'pathfuse bench' per map entry and "
        "planner configuration (and every entry pooled): runs, success rate with a 95%% "
        "Wilson interval, errors (never dropped), collision-free rate, path length and "
        "planning time (mean with a 95%% t interval, median), R_length against a reference "
        "(paired on the same problem and seed, with the number of pairs), time to goal and "
        "collisions for dynamic runs; box plots per configuration, and every swept "
        "parameter against success rate and length.  Writes report.html (self-contained), "
        "report.md, summary.csv, parameters.csv and PNG figures into --out.",
        epilog=_fmt("""
examples:
  pathfuse report sweep.db --out sweep-report
  pathfuse report paper.db --out paper-report --reference fusion
  pathfuse report sweep.db --out r1 --param r1_m --param step_m
  pathfuse report paper.db --out paper-report --reference 'fusion(r1_m=1)'

--reference takes a planner configuration name as the tables show it, or a planner
with one configuration; by default R_length is against the experiment's own reference
(its 'reference:' planner, or the optimum of MovingAI scen lines).
"""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    r.add_argument("db", metavar="STUDY.db", help="study database written by pathfuse bench")
    r.add_argument("--out", default="report-out", help="output folder (default report-out)")
    r.add_argument("--reference", metavar="PLANNER_OR_CONFIG",
                   help="R_length reference (default: the experiment's reference)")
    r.add_argument("--param", action="append", metavar="NAME",
                   help="parameter to plot against success rate and length, repeatable "
                   "(default: every swept parameter)")
    r.add_argument("--link-images", action="store_true",
                   help="link the PNGs from report.html instead of embedding them")
    r.set_defaults(func=cmd_report)

    q = sub.add_parser(
        "planners", help="list the registered planners and their parameters",
        description="List every planner in the registry: its global planner and controller, "
        "whether it runs offline (pathfuse plan) and online (pathfuse simulate), and its "
        "parameters with their defaults.",
        epilog="examples:\n  pathfuse planners\n  pathfuse planners --params\n"
               "  pathfuse planners --json",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    q.add_argument("--params", action="store_true",
                   help="explain every parameter: default, unit, accepted values, meaning")
    q.add_argument("--json", action="store_true", help="print JSON")
    q.set_defaults(func=cmd_planners)

    return parser


_POINT_OPTIONS = ("--start", "--goal")


def _join_negative_values(argv: Sequence[str]) -> list[str]:
    """``--start -1,-0.5`` -> ``--start=-1,-0.5`` (argparse would take ``-1,...`` for an option)."""
    out: list[str] = []
    it = iter(argv)
    for tok in it:
        if tok in _POINT_OPTIONS:
            nxt = next(it, None)
            if nxt is not None and nxt[:1] == "-" and (nxt[1:2].isdigit() or nxt[1:2] == "."):
                out.append(f"{tok}={nxt}")
                continue
            out.append(tok)
            if nxt is not None:
                out.append(nxt)
            continue
        out.append(tok)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``pathfuse`` console script."""
    parser = build_parser()
    argv = _join_negative_values(sys.argv[1:] if argv is None else list(argv))
    args = parser.parse_args(argv)
    if not getattr(args, "command", None):
        parser.print_help()
        return EXIT_USAGE
    try:
        return int(args.func(args) or 0)
    except PathfuseError as exc:
        print(f"pathfuse {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:  # output piped into e.g. `head`, which closed early
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:
        where = f" {exc.filename}" if getattr(exc, "filename", None) else ""
        print(f"pathfuse {args.command}: error:{where} {exc.strerror or exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print(f"pathfuse {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
