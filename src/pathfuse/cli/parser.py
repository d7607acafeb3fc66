"""The ``pathfuse`` argument parser and the entry point :func:`main`."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from pathfuse.cli.args import (
    EXIT_USAGE,
    MAIN_EPILOG,
    _float,
    _fmt,
    _nonneg_float,
    _nonneg_int,
    _Parser,
    _positive_float,
    _positive_int,
)
from pathfuse.cli.barn import add_barn_parser
from pathfuse.cli.commands import (
    cmd_bench,
    cmd_dynamic,
    cmd_paper,
    cmd_plan,
    cmd_planners,
    cmd_report,
    cmd_scen,
    cmd_serve,
    cmd_simulate,
)
from pathfuse.cli.irsim import add_irsim_parser
from pathfuse.cli.shipped import add_data_parser, add_examples_parser
from pathfuse.result import PathfuseError


# --------------------------------------------------------------------------- parser
def build_parser() -> argparse.ArgumentParser:
    from pathfuse._version import __version__

    parser = _Parser(
        prog="pathfuse",
        description="2-D robot path planning: exact fast A*, artificial potential fields and "
        "the A*-APF fusion planner of Ju, Luo and Yan.",
        epilog=MAIN_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"pathfuse {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    _add_plan(sub)
    _add_scen(sub)
    _add_paper(sub)
    _add_simulate(sub)
    _add_dynamic(sub)
    add_barn_parser(sub)
    add_irsim_parser(sub)
    add_examples_parser(sub)
    add_data_parser(sub)
    _add_bench(sub)
    _add_report(sub)
    _add_planners(sub)
    _add_serve(sub)
    return parser


def _add_plan(sub: argparse._SubParsersAction) -> None:
    """``pathfuse plan``: plan one path."""
    p = sub.add_parser(
        "plan",
        help="plan one path on a map and print (or plot) the result",
        description="Plan one path on a map.  Coordinates are world coordinates in metres "
        "(ROS convention: origin = lower-left corner of cell (0, 0)).",
        epilog=_fmt(r"""
examples:
  pathfuse plan --map paper --seed 3 --planner astar --plot plan.png
  pathfuse plan --map tests/data/ros/nav2_tb3_sandbox/tb3_sandbox.yaml --start -1.0,-0.5 \
      --goal 1.5,0.5 --robot-radius 0.1
  pathfuse plan --map tests/data/ros/nav2_tb3_sandbox/tb3_sandbox.pgm --resolution 0.05 \
      --start 9.0,9.5 --goal 11.5,10.5 --json
  pathfuse plan --map paper --planner astar --param heuristic=octile
  pathfuse plan --map paper --planner fusion --global-planner thetastar

--map accepts: 'paper' (the paper's random 15 m map, --seed N), a MovingAI .map,
a ROS map_server .yaml, an inline-rows .yaml, or a .png/.pgm/.npy (with --resolution).
"""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--map", required=True, help="map file, or 'paper'")
    p.add_argument("--start", help="start X,Y in metres (default for --map paper: 1,1)")
    p.add_argument("--goal", help="goal X,Y in metres (default for --map paper: 11,11)")
    p.add_argument("--planner", default="astar", help="planner name (see 'pathfuse planners')")
    p.add_argument("--global-planner", metavar="NAME",
                   help="the global planner whose path the controller follows (default: "
                   "the planner's own; see 'pathfuse planners')")
    p.add_argument("--param", action="append", metavar="KEY=VALUE",
                   help="planner parameter, repeatable (e.g. --param heuristic=octile)")
    p.add_argument("--resolution", type=_float, help="metres per cell for image/.npy maps")
    p.add_argument("--seed", type=int, default=0, help="seed of --map paper (default 0)")
    p.add_argument("--unknown", choices=["occupied", "free"], default="occupied",
                   help="what the unknown cells of a ROS map are (default occupied)")
    p.add_argument("--robot-radius", type=_nonneg_float, default=0.0,
                   help="radius of a disc robot in metres: the path keeps this clearance "
                   "from obstacles and the map's edge (default 0)")
    p.add_argument("--time-limit", type=_float, help="planning time limit in seconds")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="OUT.png", help="write a PNG figure of the plan")
    p.set_defaults(func=cmd_plan)


def _add_scen(sub: argparse._SubParsersAction) -> None:
    """``pathfuse scen``: check A* against a scenario file."""
    s = sub.add_parser(
        "scen",
        help="check A* against a MovingAI scenario file's optimal lengths",
        description="Run the lines of a MovingAI .scen file through A* (8-connected, sqrt(2) "
        "diagonals, no corner cutting) and count how many match the file's optimal length.  "
        "Exit status 1 on any mismatch.",
        epilog=_fmt(r"""
examples:
  pathfuse scen tests/data/movingai/den312d.map tests/data/movingai/den312d.map.scen
  pathfuse scen tests/data/movingai/maze-32-32-2.map \
      tests/data/movingai/maze-32-32-2-random-1.scen --limit 100 --heuristic euclidean
"""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    s.add_argument("map", help="MovingAI .map file")
    s.add_argument("scen", help="MovingAI .scen file for that map")
    s.add_argument("--limit", type=_positive_int, help="check only the first N lines")
    s.add_argument("--heuristic", default="octile", choices=["octile", "euclidean"],
                   help="A* heuristic (default octile; both are exact)")
    s.add_argument("--tol", type=_float, default=1e-6, help="relative tolerance (default 1e-6)")
    s.add_argument("--quiet", action="store_true",
                   help="no progress display (default on stderr: a live bar on a terminal, a "
                   "few plain lines otherwise)")
    s.set_defaults(func=cmd_scen)


def _add_paper(sub: argparse._SubParsersAction) -> None:
    """``pathfuse paper``: the paper's tables."""
    pp = sub.add_parser(
        "paper",
        help="reproduce the paper's Tables I and II and Fig. 3 over many seeded maps",
        description="Run the paper's setup (15 m map, start (1, 1), goal (11, 11), 50 random "
        "obstacles, K_att 40, K_rep 5, rho_0 2 m) with all five planners on N seeded maps and "
        "write Tables I and II (one map and statistics over all maps) as Markdown and CSV, "
        "Fig. 3 and a box plot of R_length into --out. Every table also holds A* with "
        "line-of-sight smoothing, Theta* and the true shortest path, and each planner's excess "
        "over the shortest path. --variant paper runs apf, ref6, ref7 and fusion as printed "
        "(eq. 8, no escape, the full step along the force: a step that touches an obstacle is "
        "a COLLISION; no stall test); --variant pathfuse with pathfuse's defaults; both (the "
        "default) gives one table per variant.",
        epilog=_fmt("""
examples:
  pathfuse paper --out paper-out
  pathfuse paper --seeds 1000 --seed 7 --out paper-1000
  pathfuse paper --seeds 1000 --variant paper --corner-cutting --out paper-as-printed
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
    _add_paper_variant_options(pp)
    pp.add_argument("--workers", type=_positive_int, default=None,
                    help="worker processes (default: every usable CPU; 1 = in this process)")
    pp.add_argument("--out", default="paper-out",
                    help="output folder (default paper-out); its study.db keeps every run, "
                    "so running the same command again resumes or reuses them")
    pp.add_argument("--quiet", action="store_true",
                    help="no progress display (default on stderr: a live bar on a terminal, a "
                    "few plain lines otherwise)")
    pp.set_defaults(func=cmd_paper)


def _add_simulate(sub: argparse._SubParsersAction) -> None:
    """``pathfuse simulate``: one moving-obstacle episode."""
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
  pathfuse simulate head_on --planner fusion
  pathfuse simulate examples/scenarios/head_on.yaml --planner astar --gif head_on.gif
  pathfuse simulate examples/scenarios/corridor_crowd.yaml --planner dwa --robot model=diff-drive
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
    sm.add_argument("scenario", help="scenario YAML file, or the name of a shipped one "
                    "('pathfuse examples' lists them)")
    sm.add_argument("--planner", help="planner (default: the scenario's)")
    sm.add_argument("--global-planner", metavar="NAME",
                    help="the global planner whose path the controller follows (default: "
                   "the planner's own; see 'pathfuse planners')")
    sm.add_argument("--param", action="append", metavar="KEY=VALUE",
                    help="planner parameter, repeatable (e.g. --param repulsion=velocity)")
    sm.add_argument("--seed", type=_nonneg_int, default=None,
                    help="episode seed: mixed into random walks and, where the scenario has "
                         "a perturb: section, draws the discs' jitter (default: the "
                         "scenario's)")
    sm.add_argument("--robot", action="append", metavar="KEY=VALUE",
                    help="override a key of the scenario's robot: block, repeatable (e.g. "
                    "--robot model=diff-drive --robot clearance=0.1)")
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


def _add_dynamic(sub: argparse._SubParsersAction) -> None:
    """``pathfuse dynamic``: the moving-obstacle benchmark."""
    dy = sub.add_parser(
        "dynamic",
        help="benchmark the online planners among moving obstacles",
        description="Run every online planner (or --planners) on the same N generated "
        "scenarios per number of moving discs (paper map family, start (1, 1), goal (11, 11), "
        "discs aimed across the route; deterministic in --seed) and write, into --out: "
        "dynamic.md (success, collision, timeout and local-minimum rates with 95% Wilson "
        "intervals, path length and time to goal over the successful episodes, a paired "
        "comparison with the fusion), summary.csv, episodes.csv (one row per episode, nothing "
        "dropped), paired.csv and success_vs_moving.png; its study.db keeps every episode.",
        epilog=_fmt("""
examples:
  pathfuse dynamic
  pathfuse dynamic --seeds 50 --moving 0 2 4 8 --out dynamic-out
  pathfuse dynamic --seeds 100 --moving 0 4 8 12 --speed 0.5,1.0 --planners fusion,astar-replan
  pathfuse dynamic --seeds 200 --workers 2 --param fusion.repulsion=velocity --out velocity
  pathfuse dynamic --seeds 200 --robot model=diff-drive --out dynamic-diff-drive
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
    dy.add_argument("--robot", action="append", metavar="KEY=VALUE",
                    help="a key of the scenarios' robot: block, repeatable (e.g. --robot "
                    "model=diff-drive --robot clearance=0.1; default: holonomic, radius 0.2 m, "
                    "1 m/s)")
    dy.add_argument("--workers", type=_positive_int, default=None,
                    help="worker processes (default: every usable CPU; 1 = in this process)")
    dy.add_argument("--out", default="dynamic-out",
                    help="output folder (default dynamic-out); its study.db keeps every "
                    "episode, so running the same command again resumes or reuses them")
    dy.add_argument("--quiet", action="store_true",
                    help="no progress display (default on stderr: a live bar on a terminal, a "
                    "few plain lines otherwise)")
    dy.set_defaults(func=cmd_dynamic)


def _add_bench(sub: argparse._SubParsersAction) -> None:
    """``pathfuse bench``: a benchmark sweep."""
    b = sub.add_parser(
        "bench",
        help="run (or resume) a benchmark sweep into a study database",
        description="Run every run of an experiment file (maps x seeds x queries x planners "
        "x parameter combinations) and store each in an SQLite study database in OMPL's "
        "benchmark layout.  Runs already stored are skipped, so running the same command "
        "again resumes an interrupted sweep.  Exit status 0 when no run raised, 1 when some "
        "did (they are stored as ERROR with their traceback) or the Dask cluster was lost "
        "(the unfinished runs stay missing), 2 for a bad experiment file or argument, or a "
        "database that is damaged, read-only, not a study or being written by another "
        "sweep, 130 when interrupted (Ctrl-C) and 143 on SIGTERM (what finished is stored).",
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
    b.add_argument("experiment", help="experiment YAML file, or the name of a shipped one "
                   "('pathfuse examples' lists them)")
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
    b.add_argument("--worker-wait", type=_positive_float, default=60.0, metavar="SECONDS",
                   help="with --scheduler: how long to wait when the cluster has no worker "
                   "left before stopping (default 60; it says so after 5 s)")
    b.add_argument("--batch-size", type=_positive_int, default=None,
                   help="runs per task (default: about 8 tasks per worker, at most 64)")
    b.add_argument("--retry-errors", action="store_true",
                   help="run again the runs stored as ERROR")
    b.add_argument("--no-progress", action="store_true",
                   help="no progress display (default on stderr: a live bar on a terminal, a "
                   "few plain lines otherwise)")
    b.set_defaults(func=cmd_bench)


def _add_report(sub: argparse._SubParsersAction) -> None:
    """``pathfuse report``: a study's tables and figures."""
    r = sub.add_parser(
        "report",
        help="tables and figures of a study database (Markdown, CSV, PNG, HTML)",
        description="Summarise a study database of 'pathfuse bench' per map entry and "
        "planner configuration (and every entry pooled): runs, success rate with a 95% "
        "Wilson interval, errors (never dropped), collision-free rate, path length and "
        "planning time (mean with a 95% t interval, median), R_length against a reference "
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


def _add_planners(sub: argparse._SubParsersAction) -> None:
    """``pathfuse planners``: the registry's planners."""
    q = sub.add_parser(
        "planners", help="list the registered planners and their parameters",
        description="List every planner in the registry: its global planner and controller, "
        "whether it runs offline (pathfuse plan) and online (pathfuse simulate), and its "
        "parameters with their defaults; then the global planners and the controllers "
        "(plug-ins' included).",
        epilog="examples:\n  pathfuse planners\n  pathfuse planners --params\n"
               "  pathfuse planners --json",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    q.add_argument("--params", action="store_true",
                   help="explain every parameter: default, unit, accepted values, meaning")
    q.add_argument("--json", action="store_true", help="print JSON")
    q.set_defaults(func=cmd_planners)


def _port(text: str) -> int:
    """An argparse type: a TCP port, 0 (any free port) to 65535."""
    try:
        v = int(text)
    except ValueError:
        v = -1
    if not 0 <= v <= 65535:
        raise argparse.ArgumentTypeError(f"must be a port from 0 to 65535 (0: any free "
                                         f"port), got {text[:40]!r}")
    return v


def _add_serve(sub: argparse._SubParsersAction) -> None:
    """``pathfuse serve``: the planning playground in the browser."""
    w = sub.add_parser(
        "serve", help="the planning playground in the browser (pip install \"pathfuse[web]\")",
        description="Start a local web app: draw or load a map, drag start and goal, run "
        "any registered planners side by side, look at the potential field, the A* closed "
        "set and the c-space, and play moving-obstacle episodes.  Its JSON API is "
        "documented in docs/guide/playground.md.  Binds to 127.0.0.1 unless --host says "
        "otherwise, and "
        "answers requests that name a loopback host (localhost, 127.0.0.1, ::1) unless "
        "--allow-host adds names.  Every computation runs in a worker process that is "
        "stopped at the --budget.",
        epilog=_fmt("""
examples:
  pathfuse serve --open
  pathfuse serve --port 8080 --maps tests/data/movingai
  pathfuse serve --host 0.0.0.0 --allow-host mybox.lan   # reachable from other machines

Needs the web extra: pip install "pathfuse[web]".
"""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    w.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    w.add_argument("--port", type=_port, default=8000,
                   help="port, 0 to 65535 (default 8000; 0: any free port)")
    w.add_argument("--allow-host", action="append", metavar="NAME",
                   help="a host name requests may use besides localhost, 127.0.0.1 and ::1 "
                   "(and --host), repeatable; '*' allows any (DNS rebinding can then reach "
                   "the app)")
    w.add_argument("--open", action="store_true", help="open the page in a web browser")
    w.add_argument("--maps", action="append", metavar="DIR",
                   help="a folder of maps and scenario files to offer, repeatable (default: "
                   "examples/ and tests/data/ of the source tree, when present)")
    w.add_argument("--budget", type=_positive_float, default=8.0,
                   help="seconds one request may take, waiting for a worker included; its "
                   "worker process is stopped 1 s past it (default 8)")
    w.add_argument("--max-cells", type=_positive_int, default=2048 * 2048,
                   help="cells of any map (default 4194304 = 2048 x 2048)")
    w.add_argument("--max-upload-mb", type=_positive_int, default=32,
                   help="size of an upload in MiB (default 32)")
    w.add_argument("--workers", type=_positive_int, default=3,
                   help="worker processes: requests computed at once (default 3)")
    w.add_argument("--queue", type=_nonneg_int, default=32,
                   help="requests that may wait for a worker; more are answered 503 with "
                   "Retry-After (default 32)")
    w.add_argument("--no-warm", action="store_true",
                   help="do not compile the planners' kernels when the server starts")
    w.add_argument("--log-level", default="warning",
                   choices=["critical", "error", "warning", "info", "debug"],
                   help="uvicorn's log level (default warning)")
    w.set_defaults(func=cmd_serve)


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


def _one_line_warnings(command: str) -> None:
    """Warnings (a ROS map's yaw, ...) as one line ``pathfuse CMD: warning: ...`` on stderr,
    without Python's file, line and source line."""
    import warnings

    def show(message, category, filename, lineno, file=None, line=None):  # noqa: ANN001
        text = " ".join(str(message).split())
        print(f"pathfuse {command}: warning: {text}", file=file or sys.stderr)

    warnings.showwarning = show


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``pathfuse`` console script."""
    parser = build_parser()
    argv = _join_negative_values(sys.argv[1:] if argv is None else list(argv))
    args = parser.parse_args(argv)
    if not getattr(args, "command", None):
        parser.print_help()
        return EXIT_USAGE
    _one_line_warnings(args.command)
    from pathfuse.sigterm import terminate_like_ctrl_c

    terminate_like_ctrl_c()  # SIGTERM ends a command like Ctrl-C: one line, stored runs kept
    try:
        return int(args.func(args) or 0)
    except PathfuseError as exc:
        print(f"pathfuse {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except (MemoryError, RecursionError) as exc:  # a last guard: the limits should come first
        what = "out of memory" if isinstance(exc, MemoryError) else "input nested too deeply"
        print(f"pathfuse {args.command}: error: {what}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:  # output piped into e.g. `head`, which closed early
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:
        where = f" {exc.filename}:" if getattr(exc, "filename", None) else ""
        print(f"pathfuse {args.command}: error:{where} {exc.strerror or exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt as exc:
        sig = getattr(exc, "signame", "")
        how = f"terminated ({sig})" if sig else "interrupted"
        summary = getattr(exc, "summary", None)  # a sweep: its finished runs are stored
        tail = ""
        if summary is not None:
            tail = (f"; {summary.skipped + summary.ran}/{summary.total} runs stored in "
                    f"{summary.db_path}, run the same command again to finish the rest")
        print(f"pathfuse {args.command}: {how}{tail}", file=sys.stderr)
        return 143 if sig == "SIGTERM" else 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())


def _add_paper_variant_options(pp: argparse.ArgumentParser) -> None:
    """``pathfuse paper``'s variant, corner rule and references."""
    pp.add_argument("--variant", choices=["both", "pathfuse", "paper"], default="both",
                    help="the stepping planners with pathfuse's defaults, as printed in the "
                    "paper, or both, one table each (default both)")
    pp.add_argument("--corner-cutting", action="store_true",
                    help="the A* reference cuts corners (the paper's 14.7279 m is a "
                    "corner-cutting length); default: no corner cutting")
    pp.add_argument("--no-references", action="store_true",
                    help="leave out astar-smooth, thetastar and shortest (and the excess "
                    "over the shortest path)")

