"""The commands of the ``pathfuse`` command line: each parses its options and calls the library."""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from pathfuse.cli.args import (
    EXIT_FAIL,
    CliError,
    _load_map,
    output_file,
    parse_params,
    parse_planner_list,
    parse_planner_params,
    parse_point,
    parse_speed,
)
from pathfuse.result import PathfuseError
from pathfuse.validate import short as _shown


# --------------------------------------------------------------------------- commands
def cmd_plan(args: argparse.Namespace) -> int:
    import pathfuse
    from pathfuse.api import plan_query
    from pathfuse.generate import PAPER_GOAL, PAPER_START

    grid = _load_map(args)
    is_paper = str(args.map).lower() == "paper"
    if args.start is None or args.goal is None:
        if not is_paper:
            raise CliError("--start and --goal are required unless --map paper")
    start = parse_point(args.start, "--start") if args.start else PAPER_START
    goal = parse_point(args.goal, "--goal") if args.goal else PAPER_GOAL
    params = with_global_planner(parse_params(args.param), args.global_planner)
    if args.plot:
        args.plot = output_file(args.plot, "--plot", ".png")
    budget = pathfuse.Budget(time_limit_s=args.time_limit) if args.time_limit else None
    _warm_query(args.planner, params, args.robot_radius, grid.occupied.size,
                budget is not None)
    result, spec, cfg, _ = plan_query(grid, start, goal, args.planner, params, budget=budget,
                                      robot_radius_m=args.robot_radius)
    global_planner = spec.global_planner_of(cfg)
    if args.plot:
        from pathfuse.viz import plot_plan

        plot_plan(
            grid, result, start, goal, args.plot,
            title=f"{grid.name}: {args.planner} {result.status.name} {result.length:.3f} m",
            astar_points=result.info.get("astar_path"), robot_radius_m=args.robot_radius,
        )
    if args.json:
        d = result.to_dict()
        d["map"] = grid.name
        d["start"], d["goal"] = list(start), list(goal)
        d["global_planner"] = global_planner
        print(json.dumps(d))
    else:
        print(f"map       {grid.name}  ({grid.width} x {grid.height} cells, {grid.resolution:g} m)")
        also = f"  (global planner {global_planner})" if global_planner else ""
        print(f"planner   {result.planner}{also}")
        print(f"status    {result.status.name}  {result.message}")
        print(f"length    {result.length:.4f} m  ({len(result.path)} points)")
        how = ("  (kernels interpreted: not compiled yet; see PATHFUSE_KERNELS)"
               if result.info.get("kernels") == "interpreted" else "")
        print(f"time      {result.time_s * 1e3:.3f} ms{how}")
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
    _warm_with_notice("astar")
    bar = _progress(len(problems), Path(args.scen).name, "lines", args)
    for i, p in enumerate(problems):
        if i and not i % 64:
            bar.update(64)
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
    bar.update(len(problems) - bar.done)
    bar.close()
    n = n_ok + n_bad
    print(f"{Path(args.scen).name}: {n_ok}/{n} lines match the optimal length "
          f"(rel. tol {args.tol:g}); A* time {total_t:.3f} s, "
          f"{1e3 * total_t / max(n, 1):.3f} ms/query")
    for line in worst:
        print(line)
    return 0 if n_bad == 0 else EXIT_FAIL


def _progress(total: int, label: str, unit: str, args: argparse.Namespace) -> Any:
    """The progress display of a command (off with --quiet)."""
    from pathfuse.bench.progress import ProgressBar

    return ProgressBar(total, label=label, unit=unit,
                       enabled=not getattr(args, "quiet", False))


def _warm_with_notice(planner: str | Sequence[str], world: bool = False) -> None:
    """Compile the kernels of the planner(s) (and the world's) now, saying so first, in one
    line, when numba's cache is cold."""
    from pathfuse.bench.warmup import warm_kernels

    def notice(text: str) -> None:
        print(f"pathfuse: {text}", file=sys.stderr, flush=True)

    names = [planner] if isinstance(planner, str) else list(planner)
    warm_kernels(names, metrics=False, world=world, notify=notice)


def _warm_query(planner: str, params: dict[str, Any], robot_radius_m: float,
                cells: int, timed: bool) -> None:
    """Compile the kernels one plan runs (its global planner's and controller's only),
    saying so first, in one line, when numba's cache is cold; nothing when the plan, on a
    map of ``cells`` cells and without a time limit (not ``timed``), runs them interpreted
    (:mod:`pathfuse.tier`)."""
    from pathfuse.planners.registry import get_planner, make_params
    from pathfuse.planners.run import warm_query

    def notice() -> None:
        print(f"pathfuse: compiling the kernels of {planner} (first run only; cached "
              "afterwards)", file=sys.stderr, flush=True)

    spec = get_planner(planner)
    warm_query(spec, make_params(spec, params), robot_radius_m, notice, cells=cells,
               timed=timed)


def with_global_planner(params: dict[str, Any], name: str | None) -> dict[str, Any]:
    """``params`` with ``global_planner`` set from ``--global-planner`` (when given; the
    option and ``--param global_planner=...`` must agree)."""
    if name is None:
        return params
    if params.get("global_planner", name) != name:
        raise CliError(f"--global-planner {name} and --param global_planner="
                       f"{params['global_planner']} disagree")
    return {**params, "global_planner": name}


def planner_table() -> dict[str, Any]:
    """The registry's catalogue (what ``pathfuse planners --json`` prints; the playground's
    forms come from the same :func:`pathfuse.planners.registry.catalogue`)."""
    from pathfuse.planners.registry import catalogue

    return catalogue()


def cmd_planners(args: argparse.Namespace) -> int:
    table = planner_table()
    if args.json:
        print(json.dumps(table))
        return 0
    print("planners (a global planner, a controller and their parameters):\n")
    for name, d in table["planners"].items():
        runs = " and ".join(k for k in ("offline", "online") if d[k])
        also = f"; also called {', '.join(d['aliases'])}" if d["aliases"] else ""
        gp = d["global_planner"]
        if gp and d["any_global_planner"]:
            gp += " or any (global_planner)"
        parts = [f"global planner: {gp}" if gp else "",
                 f"controller: {d['controller']}" if d["controller"] else "a plug-in function"]
        print(f"{name}  ({'; '.join(x for x in parts if x)}; runs {runs}{also})")
        print(f"  {d['description']}")
        if args.params:
            for p in d["params"]:
                unit = f" {p['unit']}" if p["unit"] and p["default"] is not None else ""
                print(f"    {p['name']} = {p['default']!r}{unit}  ({p['accepts']}): {p['help']}")
        else:
            shown = ", ".join(f"{p['name']}={p['default']!r}" for p in d["params"])
            print(f"  parameters: {shown or 'none'}")
    print("\nglobal planners (--global-planner NAME, or the parameter global_planner):\n")
    for name, d in table["global_planners"].items():
        origin = f"  [plug-in {d['plugin']}]" if d["plugin"] else ""
        print(f"{name}{origin}\n  {d['description']}")
    print("\ncontrollers:\n")
    for name, d in table["controllers"].items():
        print(f"{name}  ({d['label']}): planners {', '.join(d['planners']) or 'none'}")
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
    from pathfuse.studies.paper import (
        REFERENCES,
        PaperConfig,
        run_paper,
        summary_rows,
        write_paper_outputs,
    )

    variants = ("pathfuse", "paper") if args.variant == "both" else (args.variant,)
    cfg = PaperConfig(
        n_seeds=args.seeds, first_seed=args.first_seed,
        figure_seed=args.seed if args.seed is not None else args.first_seed,
        step_m=args.step, variants=variants, corner_cutting=args.corner_cutting,
        references=() if args.no_references else REFERENCES,
    )
    if not cfg.first_seed <= cfg.figure_seed < cfg.first_seed + cfg.n_seeds:
        raise CliError(
            f"--seed {cfg.figure_seed} is not among the maps run "
            f"({cfg.first_seed}..{cfg.first_seed + cfg.n_seeds - 1})"
        )
    run = run_paper(cfg, progress=False if args.quiet else None, workers=args.workers,
                    db_path=_study_db(args.out))
    files = write_paper_outputs(run, args.out)
    print(_paper_headline(len(run.records), cfg.n_seeds, run.wall_s, run.summary))
    print(f"{'variant':<9} {'planner':<13} {'success':>12} {'length mean':>12} {'R_length':>10} "
          f"{'excess':>9} {'time mean':>11}")
    for r in summary_rows(run):
        rl = ("-" if r["is_fusion"] else "n/a" if not r["r_length_pairs"]
              else f"{100 * r['r_length_mean']:+.2f}%")
        ex = "-" if not r["excess_pairs"] else f"{100 * r['excess_mean']:+.2f}%"
        lm = f"{r['length_mean_m']:.4f}m" if r["successes"] else "n/a"
        print(f"{r['variant']:<9} {r['planner']:<13} {r['successes']:>5}/{r['maps']:<6} "
              f"{lm:>12} {rl:>10} {ex:>9} {1e3 * r['time_mean_s']:>9.3f}ms")
    for path in files.values():
        print(f"wrote {path}")
    return 0


def _paper_headline(n_runs: int, n_maps: int, wall_s: float, sm: Any) -> str:
    """The first line ``pathfuse paper`` prints: how many runs, how many ran now and how fast.

    ``sm`` is the run's :class:`~pathfuse.bench.runner.RunSummary` (``ran``, ``skipped``,
    ``runs_per_s``, ``workers``, ``compile_s``, ``db_path``).

    >>> from types import SimpleNamespace as S
    >>> _paper_headline(1200, 100, 26.27, S(ran=1200, skipped=0, runs_per_s=45.7, workers=2,
    ...                                     compile_s=0.0, db_path="p/study.db"))
    '1200 runs on 100 maps in 26.27 s (46 runs/s, 2 workers)'
    >>> _paper_headline(1200, 100, 0.5, S(ran=0, skipped=1200, runs_per_s=0.0, workers=1,
    ...                                   compile_s=0.0, db_path="p/study.db"))
    '1200 runs on 100 maps, all already in p/study.db'
    """
    what = f"{n_runs} run{'' if n_runs == 1 else 's'} on {n_maps} map{'' if n_maps == 1 else 's'}"
    if sm.ran == 0 and sm.skipped:
        return f"{what}, all already in {sm.db_path}"
    how = (f"in {wall_s:.2f} s ({sm.runs_per_s:.0f} runs/s, {sm.workers} "
           f"worker{'s' if sm.workers != 1 else ''}"
           + (f", {sm.compile_s:.1f} s of it compiling kernels" if sm.compile_s >= 1.0 else "")
           + ")")
    if not sm.skipped:
        return f"{what} {how}"
    return f"{what}: {sm.ran} ran {how}, the other {sm.skipped} were already in {sm.db_path}"


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
    from pathfuse.shipped import resolve

    args.scenario = resolve(args.scenario, "scenario")
    sc = load_scenario(args.scenario)
    params = with_global_planner(parse_params(args.param), args.global_planner)
    if args.planner is None or args.planner == sc.planner.name:
        # the scenario's own planner keeps the scenario's parameters (--param overrides them)
        name, params = args.planner or sc.planner.name, {**dict(sc.planner.params), **params}
    else:
        name = args.planner
    choice = {"name": name, "params": params}
    robot = None
    if args.robot:
        robot = {**sc.robot.to_dict(), **_robot_block(args.robot)}
    from pathfuse.planners.registry import get_planner, make_params

    # the planner and its parameters are checked before the compile notice, so that a bad
    # --param is one line on stderr whether numba's cache is cold or warm
    make_params(get_planner(name), params)
    _warm_with_notice(str(choice["name"]), world=True)
    ep = simulate(sc, planner=choice, seed=args.seed, robot=robot)
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
            return "-" if not math.isfinite(v) else f"{v:.3f} m"

        print(f"distance  {gap(ep.min_distance_m)} min to any obstacle  (moving: "
              f"{gap(ep.min_obstacle_distance_m)}, static: {gap(ep.min_static_clearance_m)})")
        print(f"planning  {1e6 * ep.mean_plan_time_s:.1f} us/tick mean, "
              f"{1e3 * ep.setup_time_s:.2f} ms setup")
        if anim is not None:
            print(f"animation {anim.path}  ({anim.n_frames} frames, every {anim.frame_step} "
                  f"tick{'s' if anim.frame_step != 1 else ''}, {anim.fps:g} fps = "
                  f"{anim.speedup(dt):g}x real time, {anim.render_s:.2f} s to write)")
    return 0 if ep.reached else EXIT_FAIL


def dynamic_headline(run: Any) -> str:
    """What ``pathfuse dynamic`` ran and how fast, counted in words."""
    from pathfuse.stats import counted

    c, n = run.config, len(run.records)
    return (f"{counted(n, 'episode')} ({counted(len(c.planners), 'planner')} x "
            f"{counted(len(c.moving), 'disc count')} x {counted(c.n_seeds, 'scenario')}) in "
            f"{run.wall_s:.2f} s ({run.episodes_per_s:.1f} episodes/s, "
            f"{counted(run.workers, 'worker')})")


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
        params=parse_planner_params(args.param), robot=_robot_block(args.robot),
    )
    run = run_dynamic(cfg, progress=False if args.quiet else None, workers=args.workers,
                      db_path=_study_db(args.out))
    files = write_dynamic_outputs(run, args.out)
    print(dynamic_headline(run))
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



def _robot_block(items: Any) -> dict[str, Any]:
    """``--robot KEY=VALUE`` items as a robot block (values read as YAML scalars)."""
    from pathfuse.cli.args import parse_params

    try:
        return dict(parse_params(items))
    except CliError as exc:
        raise CliError(str(exc).replace("--param", "--robot")) from None


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
        raise CliError(f"--seeds: must be a count N >= 1, a range A:B with 0 <= A < B, "
                       f"or a list A,B,C of seeds >= 0, got {_shown(text)}") from None


def _announce_imports(path: str) -> None:
    """Name on stderr, before they run, the modules an experiment file's ``imports:`` loads
    (an experiment file with imports is code).  A file that cannot be read is left to the
    experiment loader, which words the error."""
    from pathfuse.safeyaml import read_yaml

    try:
        doc = read_yaml(path, "experiment")
    except PathfuseError:
        return
    imports = doc.get("imports") if isinstance(doc, dict) else None
    if isinstance(imports, str):
        imports = [imports]
    if isinstance(imports, list) and imports:
        names = ", ".join(str(i) for i in imports)
        print(f"pathfuse bench: importing {names} (the experiment file's 'imports:' runs "
              "this code)", file=sys.stderr, flush=True)


def _quiet_dask_logs() -> None:
    """Dask logs a lost scheduler as tracebacks; the command says it in one line instead."""
    import logging

    try:
        import distributed  # type: ignore[import-not-found]  # noqa: F401 - sets its levels
    except ImportError:
        return  # run_bench says how to install it
    for name in ["distributed", *logging.root.manager.loggerDict]:
        if name == "distributed" or name.startswith("distributed."):
            logging.getLogger(name).setLevel(logging.CRITICAL)


def cmd_bench(args: argparse.Namespace) -> int:
    from pathfuse.bench import ClusterLost, SweepInterrupted, run_bench
    from pathfuse.shipped import resolve

    seeds = None if args.seeds is None else parse_seeds(args.seeds)
    args.experiment = resolve(args.experiment, "experiment")
    _announce_imports(args.experiment)
    if args.scheduler:  # a lost cluster is one line of ours, not Dask's tracebacks
        _quiet_dask_logs()
    try:
        summary = run_bench(args.experiment, args.db, seeds=seeds, workers=args.workers,
                            scheduler=args.scheduler,
                            progress=False if args.no_progress else None,
                            retry_errors=args.retry_errors, batch_size=args.batch_size,
                            worker_wait_s=args.worker_wait)
    except SweepInterrupted as exc:
        print(exc.summary, flush=True)
        sig = getattr(exc, "signame", "")
        how = f"terminated ({sig})" if sig else "interrupted"
        print(f"pathfuse bench: {how}; run the same command again to resume", file=sys.stderr)
        return 143 if sig == "SIGTERM" else 130
    except ClusterLost as exc:
        if exc.summary is not None:
            print(exc.summary, flush=True)
        print(f"pathfuse bench: error: {exc}", file=sys.stderr)
        return EXIT_FAIL
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
    excess = any(r.get("excess_pairs") for r in shown)
    head: tuple[str, ...] = ("scope", "configuration", "runs", "success", "errors",
                             "length mean", "R_length")
    if excess:
        head += ("excess over shortest",)
    table = [head]
    for r in shown:
        rl = "n/a" if not r["r_length_pairs"] else \
            f"{100 * r['r_length_mean']:+.2f}% (n={r['r_length_pairs']})"
        lm = "n/a" if not r["length_n"] else f"{r['length_mean_m']:.3f} m"
        line: tuple[str, ...] = (r["scope"], r["config"], str(r["runs"]),
                                 f"{100 * r['success_rate']:.1f}%", str(r["errors"]), lm, rl)
        if excess:
            line += ("-" if not r.get("excess_pairs") else
                     f"{100 * r['excess_mean']:+.2f}% (n={r['excess_pairs']})",)
        table.append(line)
    widths = [max(len(row[i]) for row in table) for i in range(len(head))]
    for row in table:
        print("  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip())
    print(f"wrote {len(files)} files into {args.out}: report.html, report.md, summary.csv, "
          "parameters.csv and the figures")
    return 0




def cmd_serve(args: argparse.Namespace) -> int:
    """``pathfuse serve``: the planning playground in the browser (uvicorn + Starlette)."""
    try:
        import uvicorn  # noqa: F401 - the extra's check

        from pathfuse.web.app import default_map_folders
        from pathfuse.web.maps import Limits
        from pathfuse.web.serve import serve
    except ImportError as exc:
        raise CliError(f"the web app needs its extra: pip install \"pathfuse[web]\" "
                       f"({exc.name} is missing)") from None
    folders = default_map_folders()
    for folder in args.maps or []:
        p = Path(folder).expanduser()
        if not p.is_dir():
            raise CliError(f"--maps: {p} is not a folder")
        folders.append((p.resolve().name, p))
    limits = Limits(max_cells=args.max_cells, max_upload_bytes=args.max_upload_mb * 1024 * 1024,
                    time_budget_s=args.budget)
    return serve(host=args.host, port=args.port, map_folders=folders, limits=limits,
                 workers=args.workers, max_queue=args.queue, warm=not args.no_warm,
                 allow_hosts=args.allow_host or [], open_browser=args.open,
                 log_level=args.log_level)
