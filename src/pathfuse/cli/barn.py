"""``pathfuse barn DIR``: the BARN challenge's protocol on a folder of Gazebo worlds."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from pathfuse.cli.args import _fmt, _nonneg_int, _Parser, _positive_float, _positive_int

__all__ = ["add_barn_parser", "cmd_barn"]


def add_barn_parser(sub: Any) -> None:
    """Register the ``barn`` sub-command on the parser's sub-parsers."""
    # the Jackal's radius and speed of pathfuse.studies.barn, written out: importing that
    # module here would load numpy for every `pathfuse --help` (tests/test_cli_startup.py
    # checks that they agree)
    radius, speed = 0.333, 2.0
    b: _Parser = sub.add_parser(
        "barn",
        help="run the BARN challenge's protocol on its Gazebo worlds",
        description="Run every online planner (or --planners) through the BARN challenge's "
        "protocol on every world of DIR (worlds/world_N.world[.gz] with path_files/path_N.npy "
        "beside worlds/, as the challenge ships them): start (-2, 3) facing +y, goal (-2, 13) "
        "reached within 1 m, 100 s limit, a Jackal-sized disc robot; the challenge's optimal "
        "time (reference path length / 2 m/s) and metric (success x optimal_time / "
        "clip(time, 2 optimal_time, 8 optimal_time)).  Prints a table per planner (success, "
        "collision, timeout, mean metric, mean time, with 95% intervals) next to the "
        "challenge's published DWA baseline (measured in Gazebo: a reference line, not a "
        "like-for-like comparison) and writes barn.md, summary.csv, episodes.csv, a figure "
        "of the outcomes and mean metric by planner (barn_planners.png) and one of every "
        "planner's trajectory on one world (barn_world_N.png) into --out; --out/study.db "
        "keeps every episode, so the same command resumes.",
        epilog=_fmt("""
examples:
  pathfuse barn tests/data/barn --worlds 0-20 --planners fusion,astar-replan
  pathfuse barn experiments/barn-jackal.yaml --out barn-jackal
  pathfuse barn tests/data/barn --planners fusion --json > episodes.jsonl
  pathfuse barn tests/data/barn --resolution 0.1 --workers 2 --out barn-out
  pathfuse barn tests/data/barn --scheduler tcp://10.0.0.5:8786
"""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    b.add_argument("target", metavar="DIR|FILE.yaml",
                   help="a BARN folder (worlds/ and path_files/, or the worlds/ folder itself) "
                   "or a BARN experiment file (experiments/barn-*.yaml: folder, worlds, "
                   "planners, resolution, robot, params); options given override the file")
    b.add_argument("--planners", metavar="A,B,...",
                   help="online planners, comma-separated (default: every online planner)")
    b.add_argument("--worlds", metavar="I,J-K,...",
                   help="world indices and inclusive ranges, e.g. 0-49,100 (default: all)")
    b.add_argument("--resolution", type=_positive_float, default=None,
                   help="grid resolution the worlds are rasterised at, m (default 0.05)")
    b.add_argument("--robot-model", choices=("diff-drive", "holonomic"), default=None,
                   help="the robot's kinematics (default diff-drive: a Jackal-like base; "
                   "holonomic: pathfuse's point robot that changes velocity at once)")
    b.add_argument("--robot-radius", type=_positive_float, default=None,
                   help=f"radius of the disc robot, m (default {radius:g}: the "
                   "Jackal's body fits in it at any heading)")
    b.add_argument("--max-speed", type=_positive_float, default=None,
                   help=f"speed limit, m/s (default {speed:g}, the Jackal's)")
    b.add_argument("--dt", type=_positive_float, default=None,
                   help="simulation tick, s (default 0.1)")
    b.add_argument("--param", action="append", metavar="PLANNER.KEY=VALUE",
                   help="planner parameter, repeatable (e.g. --param fusion.r1_m=1.0)")
    b.add_argument("--workers", type=_positive_int, default=None,
                   help="worker processes (default: every usable CPU; 1 = in this process)")
    b.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                   help="run on a Dask distributed cluster (its workers must see DIR at the "
                   "same path; pip install 'pathfuse[dask]')")
    b.add_argument("--out", default="barn-out",
                   help="output folder (default barn-out); its study.db keeps every episode")
    b.add_argument("--figure-world", type=_nonneg_int, default=None, metavar="N",
                   help="the world whose trajectories barn_world_N.png shows (default: the "
                   "one where the planners' outcomes differ most)")
    b.add_argument("--json", action="store_true",
                   help="print one JSON object per episode on stdout (world, planner, status, "
                   "time_s, metric, robot_radius_m, trajectory [[t, x, y, yaw], ...], ...) "
                   "instead of the table")
    b.add_argument("--quiet", action="store_true",
                   help="no progress bar (default: a bar on stderr when it is a terminal)")
    b.set_defaults(func=cmd_barn)


def cmd_barn(args: argparse.Namespace) -> int:
    from pathfuse.cli.args import parse_planner_list, parse_planner_params
    from pathfuse.cli.commands import _study_db, _warm_with_notice
    from pathfuse.shipped import examples, resolve
    from pathfuse.studies.barn import BarnConfig, jackal_robot, load_barn_file, run_barn
    from pathfuse.studies.barn_report import (
        json_lines,
        summary_rows,
        text_table,
        write_barn_outputs,
    )

    if not Path(args.target).expanduser().exists():  # a shipped experiment file by name?
        stem = args.target[:-5] if args.target.endswith(".yaml") else args.target
        if stem in {e.name for e in examples("experiment")}:
            args.target = resolve(args.target, "experiment")
    if args.target.lower().endswith((".yaml", ".yml")):
        base, _ = load_barn_file(args.target)
    else:
        base = BarnConfig(args.target)
    robot = dict(base.robot)
    if args.robot_model is not None:
        robot = {**jackal_robot(args.robot_model),
                 **{k: v for k, v in robot.items() if k != "model"},
                 "model": args.robot_model}
    for key, val in (("radius", args.robot_radius), ("max_speed", args.max_speed)):
        if val is not None:
            robot[key] = val
    planners = base.planners if args.planners is None else parse_planner_list(args.planners)
    from pathfuse.planners.registry import get_planner

    run_names = {get_planner(n).name for n in planners} if planners else set(base.planners)
    params = {**{k: dict(v) for k, v in base.params.items() if k in run_names},
              **parse_planner_params(args.param)}
    cfg = BarnConfig(base.directory,
                     worlds=base.worlds if args.worlds is None else args.worlds,
                     planners=planners,
                     resolution=base.resolution if args.resolution is None else args.resolution,
                     robot=robot, dt=base.dt if args.dt is None else args.dt, params=params)
    from pathfuse.studies.barn import find_worlds

    # the folder and the worlds are checked before the compile notice, so that a bad
    # folder or index is one line on stderr whatever numba's cache holds
    run_idx = [w.index for w in find_worlds(cfg.directory, cfg.worlds)]
    if args.figure_world is not None:
        from pathfuse.cli.args import CliError

        if args.figure_world not in run_idx:
            shown = ", ".join(map(str, run_idx[:10])) + (", ..." if len(run_idx) > 10 else "")
            raise CliError(f"--figure-world: world {args.figure_world} is not among the worlds "
                           f"run ({shown})")
    _warm_with_notice(list(cfg.planners), world=True)  # one notice for all of them
    run = run_barn(cfg, workers=args.workers, scheduler=args.scheduler,
                   db_path=_study_db(args.out), progress=False if args.quiet else None,
                   trajectories=args.json,
                   figure_world="auto" if args.figure_world is None else args.figure_world)
    files = write_barn_outputs(run, args.out)
    if args.json:
        sys.stdout.write(json_lines(run.records))
        for path in files.values():
            print(f"wrote {path}", file=sys.stderr)
        return 0
    from pathfuse.stats import counted

    print(f"{counted(len(run.records), 'episode')} ({counted(len(cfg.planners), 'planner')} x "
          f"{counted(len(run.worlds), 'world')}) in {run.wall_s:.1f} s "
          f"({counted(run.workers, 'worker')})\n")
    print(text_table(summary_rows(run.records, cfg.planners)))
    print("\nDWA (published): the challenge's baseline in Gazebo (move_base, 50 worlds x 10 "
          "runs), a reference line, not a like-for-like comparison.\n")
    for path in files.values():
        print(f"wrote {path}")
    return 0
