"""``pathfuse irsim WORLD.yaml ...``: planners among people in IR-SIM worlds."""

from __future__ import annotations

import argparse
from typing import Any

from pathfuse.cli.args import _fmt, _nonneg_int, _Parser, _positive_float, _positive_int

__all__ = ["add_irsim_parser", "cmd_irsim"]


def add_irsim_parser(sub: Any) -> None:
    """Register the ``irsim`` sub-command on the parser's sub-parsers."""
    p: _Parser = sub.add_parser(
        "irsim",
        help="run planners among people in IR-SIM worlds (pip install 'pathfuse[irsim]')",
        description="Run every online planner (or --planners) and IR-SIM's own RVO robot "
        "(irsim-rvo) through IR-SIM world files with people, for --seeds seeds each (a seed "
        "jitters the walkers' starts and speeds: N seeds are N different episodes).  "
        "pathfuse's planners drive the world's robot through "
        "pathfuse.integrations.irsim.IrsimController; IR-SIM simulates the robot, the "
        "walkers and the collisions.  Prints a table per planner and per world (success with "
        "a 95% interval, IR-SIM collisions and those the robot drove into, median minimum "
        "gap to people, time within 0.45 m of a person, time to goal, path irregularity) "
        "and writes irsim.md, summary.csv and episodes.csv into --out; --out/study.db keeps "
        "every episode, so the same command resumes.",
        epilog=_fmt("""
examples:
  pathfuse irsim examples/irsim
  pathfuse irsim examples/irsim/corridor_head_on.yaml --planners fusion,dwa,irsim-rvo --seeds 8
  pathfuse irsim examples/irsim --seeds 8 --workers 2 --out irsim-out --gif
"""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("worlds", nargs="+", metavar="WORLD.yaml|DIR",
                   help="IR-SIM world files (with one robot and its goal; pathfuse's settings in "
                   "custom: pathfuse:), or folders of them")
    p.add_argument("--planners", metavar="A,B,...",
                   help="online planners and irsim-rvo, comma-separated (default: every online "
                   "planner and irsim-rvo)")
    p.add_argument("--seeds", type=_positive_int, default=8,
                   help="seeds per world (default 8)")
    p.add_argument("--resolution", type=_positive_float, default=0.05,
                   help="cell side the static obstacles are rasterised at, m (default 0.05)")
    p.add_argument("--time-limit", type=_positive_float, default=None,
                   help="time limit of every episode, s (default: each world's)")
    p.add_argument("--param", action="append", metavar="PLANNER.KEY=VALUE",
                   help="planner parameter, repeatable (e.g. --param fusion.r1_m=1.0)")
    p.add_argument("--workers", type=_positive_int, default=None,
                   help="worker processes (default: every usable CPU; 1 = in this process)")
    p.add_argument("--out", default="irsim-out",
                   help="output folder (default irsim-out); its study.db keeps every episode")
    p.add_argument("--gif", action="store_true",
                   help="also write a GIF of every (world, planner) for seed --gif-seed into "
                   "OUT/gifs (the episode is run again: the same episode)")
    p.add_argument("--gif-seed", type=_nonneg_int, default=0, metavar="S",
                   help="the seed of the GIFs (default 0)")
    p.add_argument("--quiet", action="store_true",
                   help="no progress bar (default: a bar on stderr when it is a terminal)")
    p.set_defaults(func=cmd_irsim)


def cmd_irsim(args: argparse.Namespace) -> int:
    from pathfuse.cli.args import CliError, parse_planner_list, parse_planner_params
    from pathfuse.cli.commands import _study_db, _warm_with_notice
    from pathfuse.integrations.irsim import import_irsim
    from pathfuse.integrations.irsim_run import RVO_BASELINE
    from pathfuse.studies.irsim import (
        IrsimConfig,
        run_irsim_study,
        summary_rows,
        text_table,
        write_gifs,
        write_irsim_outputs,
    )

    import_irsim()  # a missing extra is one line, before anything runs
    cfg = IrsimConfig(tuple(args.worlds), planners=parse_planner_list(args.planners),
                      n_seeds=args.seeds, resolution_m=args.resolution,
                      params=parse_planner_params(args.param), time_limit_s=args.time_limit)
    if args.gif and args.gif_seed >= cfg.n_seeds:
        raise CliError(f"--gif-seed: seed {args.gif_seed} is not among the seeds run "
                       f"(0..{cfg.n_seeds - 1})")
    _warm_with_notice([n for n in cfg.planners if n != RVO_BASELINE], world=True)
    run = run_irsim_study(cfg, workers=args.workers, db_path=_study_db(args.out),
                          progress=False if args.quiet else None)
    files = write_irsim_outputs(run, args.out)

    from pathfuse.stats import counted

    print(f"{counted(len(run.records), 'episode')} ({counted(len(cfg.planners), 'planner')} x "
          f"{counted(len(cfg.worlds), 'world')} x {counted(cfg.n_seeds, 'seed')}) in "
          f"{run.wall_s:.1f} s ({counted(run.workers, 'worker')})\n")
    print(text_table(summary_rows(run.records, cfg.planners)))
    print()
    for path in files.values():
        print(f"wrote {path}")
    if args.gif:
        for path in write_gifs(cfg, args.out, args.gif_seed):
            print(f"wrote {path}")
    return 0
